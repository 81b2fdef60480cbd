#![doc = include_str!("../README.md")]

pub mod config;
pub mod dataset;
pub mod error;
pub mod ode;
pub mod sensor;
pub mod skin;
pub mod slip;
pub mod terrain;
pub mod trace;
pub mod track;

pub use config::{RealismParams, SimConfig};
pub use dataset::{
    DatasetSpec, HopRecord, PAPER_TABLE1, SimulatedDataset, Simulator, TrialOutput, TrialPlan,
    VelocityTable, simulate_dataset,
};
pub use error::{Result, SimError};
pub use slip::{Gait, GroundParams, HopTruth, RobotParams};
pub use terrain::{HeightMap, Terrain};
