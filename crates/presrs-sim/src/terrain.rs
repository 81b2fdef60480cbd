//! Terrain surfaces under the foot: height and local contact stiffness fields for the four terrains of the
//! paper (section IV) and for terrains given as greyscale height-map images.
//!
//! Every hop lands on a new random patch: a terrain generates, for the foot's sample points (metres in the
//! foot frame: `x` forward, `y` to the left, origin at the centre of the foot's base), the surface height
//! (m, up positive, relative to the nominal surface), the local normal stiffness of the surface layer
//! (Pa/m, in series with the skin) and its yield pressure (Pa; plastic soils cap the pressure). The patch
//! is rotated by a random yaw and shifted by a random offset, so no two hops see the same surface.
//!
//! The dimensions below are typical values of each material (assumptions, stated per field); the
//! `realism.terrain_variability` knob scales how much they vary from hop to hop.

use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{Result, param};
use crate::slip::GroundParams;

/// The surface seen by the foot's sample points on one hop.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfacePatch {
    /// Surface height at each sample point, m.
    pub height_m: Vec<f64>,
    /// Normal stiffness per unit area of the surface layer, Pa/m (`f64::INFINITY`: rigid).
    pub stiffness_pa_per_m: Vec<f64>,
    /// Pressure at which the surface yields plastically, Pa (`f64::INFINITY`: elastic).
    pub yield_pa: Vec<f64>,
}

/// Smooth pine wood planks: rigid, fine grain (latewood ridges), seams between planks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WoodParams {
    /// Macroscopic ground compliance (nearly rigid: a plank floor on joists).
    pub ground: GroundParams,
    /// Mean distance between growth rings across the grain, m (pine: 2-5 mm; assumption 2.5 mm).
    pub ring_spacing_m: f64,
    /// Fraction of a ring occupied by the harder latewood band that stands proud after wear.
    pub latewood_fraction: f64,
    /// How far latewood stands above earlywood, m (worn softwood floors: tens of micrometres).
    pub grain_relief_m: f64,
    /// Amplitude and wavelength of the grain's waviness, m.
    pub grain_waviness_m: f64,
    pub grain_waviness_wavelength_m: f64,
    /// Plank width, m (standard 3.5 in boards: 89 mm).
    pub plank_width_m: f64,
    /// Width of the seam (gap) between planks, m.
    pub seam_gap_m: f64,
    /// Standard deviation of the height step between adjacent planks, m.
    pub plank_step_sd_m: f64,
    /// Random micro-roughness, m (sanded wood: a few micrometres).
    pub roughness_m: f64,
    /// Local stiffness of the wood surface, Pa/m (pine across the grain, E ~ 0.5 GPa over ~10 mm).
    pub surface_stiffness_pa_per_m: f64,
}

impl Default for WoodParams {
    fn default() -> Self {
        Self {
            ground: GroundParams::uniform(2.0e6, 500.0),
            ring_spacing_m: 2.5e-3,
            latewood_fraction: 0.35,
            grain_relief_m: 35e-6,
            grain_waviness_m: 1.0e-3,
            grain_waviness_wavelength_m: 40e-3,
            plank_width_m: 89e-3,
            seam_gap_m: 1.5e-3,
            plank_step_sd_m: 60e-6,
            roughness_m: 4e-6,
            surface_stiffness_pa_per_m: 5.0e10,
        }
    }
}

/// Standard flooring carpet: a regular lattice of compliant pile loops.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CarpetParams {
    pub ground: GroundParams,
    /// Distance between loop rows (the gauge; 1/10 in = 2.54 mm is common), m.
    pub gauge_m: f64,
    /// Distance between loops along a row (stitch rate ~9 per inch), m.
    pub stitch_m: f64,
    /// Length and width of a loop's crown seen from above, m.
    pub loop_length_m: f64,
    pub loop_width_m: f64,
    /// How much a loop's crown drops from its centre to its edge, m.
    pub loop_crown_m: f64,
    /// Random variation of loop height and position, m. A flooring carpet's loops are tufted by machine
    /// but not on a perfect lattice; the position spread (a seventh of the stitch) is what keeps its
    /// spectrum from being a few orientation-dependent spikes (calibrated: docs/reproducing.md).
    pub loop_height_sd_m: f64,
    pub loop_position_sd_m: f64,
    /// Depth of the gaps between loops below the loop tops, m (beyond the skin's reach).
    pub pile_depth_m: f64,
    /// Local stiffness of a loop, Pa/m (nylon loop pile: soft).
    pub loop_stiffness_pa_per_m: f64,
}

impl Default for CarpetParams {
    fn default() -> Self {
        Self {
            ground: GroundParams::uniform(3.0e4, 150.0),
            gauge_m: 2.54e-3,
            stitch_m: 2.8e-3,
            loop_length_m: 2.4e-3,
            loop_width_m: 1.3e-3,
            loop_crown_m: 0.35e-3,
            loop_height_sd_m: 0.13e-3,
            loop_position_sd_m: 0.35e-3,
            pile_depth_m: 3e-3,
            loop_stiffness_pa_per_m: 6.0e7,
        }
    }
}

/// Semi-moist clay dirt: plastic, smooth with clumps; the foot sinks and the contact is large.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClayParams {
    pub ground: GroundParams,
    /// Amplitude of the smooth large-scale undulation, m, and its shortest wavelength, m.
    pub undulation_m: f64,
    pub undulation_wavelength_m: f64,
    /// Fine grit roughness, m, and its correlation length, m.
    pub grit_m: f64,
    pub grit_length_m: f64,
    /// Clumps per square metre, their radius range (m) and height range (m).
    pub clumps_per_m2: f64,
    pub clump_radius_m: [f64; 2],
    pub clump_height_m: [f64; 2],
    /// Local stiffness of the soil and of the (drier, firmer) clumps, Pa/m.
    pub soil_stiffness_pa_per_m: f64,
    pub clump_stiffness_pa_per_m: f64,
    /// Pressure at which the moist soil flows plastically, Pa.
    pub soil_yield_pa: f64,
}

impl Default for ClayParams {
    fn default() -> Self {
        Self {
            ground: GroundParams::uniform(1.5e4, 400.0),
            undulation_m: 0.25e-3,
            undulation_wavelength_m: 20e-3,
            grit_m: 15e-6,
            grit_length_m: 0.8e-3,
            clumps_per_m2: 2500.0,
            clump_radius_m: [1.5e-3, 4.0e-3],
            clump_height_m: [0.3e-3, 1.0e-3],
            soil_stiffness_pa_per_m: 3.0e7,
            clump_stiffness_pa_per_m: 1.5e8,
            soil_yield_pa: 70e3,
        }
    }
}

/// Thick grass: dense random blades and stems lying over soft soil.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GrassParams {
    /// Macroscopic compliance: an elastic canopy over soft soil (the most compliant terrain, little damping).
    pub ground: GroundParams,
    /// Mean number of blade layers covering a point.
    pub blade_layers: f64,
    /// Blade width range, m (broad-bladed turf grass: 3-6 mm).
    pub blade_width_m: [f64; 2],
    /// Blade length range, m.
    pub blade_length_m: [f64; 2],
    /// Blade thickness, m.
    pub blade_thickness_m: f64,
    /// Spread of blade directions around the lay direction of the patch, rad.
    pub blade_direction_sd_rad: f64,
    /// Stems (stolons) per square metre and their diameter, m.
    pub stems_per_m2: f64,
    pub stem_diameter_m: f64,
    /// How far the soil lies below the bottom blade layer, m.
    pub soil_gap_m: f64,
    /// Local stiffness of the blade mat and of the soil, Pa/m.
    pub blade_stiffness_pa_per_m: f64,
    pub soil_stiffness_pa_per_m: f64,
}

/// Depth of the grass canopy (blades and thatch) above the firm soil, m. Assumption for "thick" turf
/// (St. Augustine / Bahia lawns are mown at 60-100 mm; the compressible mat under a foot is ~40 mm).
pub const GRASS_CANOPY_DEPTH_M: f64 = 0.040;
/// Secant stiffness of the canopy under the foot at full canopy compression, N/m: the canopy carries
/// `k d` = 120 N (the hopper's body weight is 24.5 N, its peak stance force ~130 N) when pressed down to
/// the soil. Assumption (a 2000 mm^2 foot on a lawn sinks a few centimetres at ~50 kPa).
pub const GRASS_CANOPY_STIFFNESS_N_PER_M: f64 = 3.0e3;
/// Exponent of the canopy's stiffening, `F = k z (z / d)^(n - 1)`. A fibrous mat stiffens as it is
/// compressed: blade tips bend under almost no load, deeper down more blades and stems are engaged and
/// pack together (van Wyk's law for compressed fibre assemblies, `p ~ 1/V^3 - 1/V0^3`, and measured
/// turf load-sinkage curves are concave upward). n = 2 is the mildest such law (tangent stiffness rising
/// linearly from 0 at the tips to 2k at the soil); assumption, see the crate README for its effect.
pub const GRASS_CANOPY_EXPONENT: f64 = 2.0;
/// Viscous damping of the canopy, N s/m: little (blades bend elastically, the grass is springy; damping
/// ratio with the hopper's 2.5 kg ~0.006). Assumption, chosen with the mid-stance load in mind: the canopy
/// is compressed fastest at G3, so its damping costs G3 the most hop height and mid-stance force (peak
/// force G1/G2/G3 139/140/131 N at 1.0 N s/m, 135/134/120 N at 1.5), and the paper's classifier, trained
/// on G2, is load-sensitive (crate README, "Why grass is fastest").
pub const GRASS_CANOPY_DAMPING_N_S_PER_M: f64 = 1.0;
/// Stiffness the soil under the canopy adds once the canopy is pressed through, N/m (~30x the canopy:
/// assumption). It bounds the sinkage under a payload (README, "Load robustness").
pub const GRASS_SOIL_STIFFNESS_N_PER_M: f64 = 1.0e5;

impl Default for GrassParams {
    fn default() -> Self {
        Self {
            // Thick grass is a soft, springy, stiffening mat (most compliant, least dissipative) on firm
            // soil; see the constants above and the crate README ("Why grass is fastest").
            ground: GroundParams {
                layer_depth_m: Some(GRASS_CANOPY_DEPTH_M),
                base_stiffness_n_per_m: GRASS_SOIL_STIFFNESS_N_PER_M,
                stiffening_exponent: GRASS_CANOPY_EXPONENT,
                ..GroundParams::uniform(
                    GRASS_CANOPY_STIFFNESS_N_PER_M,
                    GRASS_CANOPY_DAMPING_N_S_PER_M,
                )
            },
            blade_layers: 2.2,
            blade_width_m: [2.5e-3, 5.0e-3],
            blade_length_m: [30e-3, 80e-3],
            blade_thickness_m: 0.35e-3,
            blade_direction_sd_rad: 0.7,
            stems_per_m2: 1500.0,
            stem_diameter_m: 1.8e-3,
            soil_gap_m: 0.3e-3,
            blade_stiffness_pa_per_m: 6.0e7,
            soil_stiffness_pa_per_m: 1.0e7,
        }
    }
}

/// Defaults for terrains given as greyscale height-map images.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImageTerrainParams {
    pub ground: GroundParams,
    /// Size of one image pixel on the ground, m.
    pub pixel_size_m: f64,
    /// Height difference between black (0) and white (full scale), m.
    pub relief_m: f64,
    /// Local stiffness of the surface, Pa/m.
    pub surface_stiffness_pa_per_m: f64,
}

impl Default for ImageTerrainParams {
    fn default() -> Self {
        Self {
            ground: GroundParams::uniform(3.0e4, 150.0),
            pixel_size_m: 0.25e-3,
            relief_m: 1.0e-3,
            surface_stiffness_pa_per_m: 8.0e7,
        }
    }
}

/// A height map given as an image (e.g. `../shared/data/textures/grass.png`), values in `[0, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightMap {
    pub width: usize,
    pub height: usize,
    /// Row-major, `width * height` values in `[0, 1]`.
    pub values: Vec<f32>,
}

impl HeightMap {
    pub fn new(width: usize, height: usize, values: Vec<f32>) -> Result<Self> {
        if width < 2 || height < 2 || values.len() != width * height {
            return Err(param(
                "height map",
                format!(
                    "need at least 2x2 values and width*height of them, got {width}x{height} with {}",
                    values.len()
                ),
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(param("height map", "values must be finite"));
        }
        Ok(Self {
            width,
            height,
            values,
        })
    }

    /// Bilinear sample at pixel coordinates, wrapping around the edges.
    fn sample(&self, px: f64, py: f64) -> f64 {
        let (w, h) = (self.width as f64, self.height as f64);
        let px = px.rem_euclid(w);
        let py = py.rem_euclid(h);
        let (x0, y0) = (px.floor(), py.floor());
        let (fx, fy) = (px - x0, py - y0);
        let (x0, y0) = (x0 as usize % self.width, y0 as usize % self.height);
        let (x1, y1) = ((x0 + 1) % self.width, (y0 + 1) % self.height);
        let v = |x: usize, y: usize| f64::from(self.values[y * self.width + x]);
        let top = v(x0, y0) * (1.0 - fx) + v(x1, y0) * fx;
        let bottom = v(x0, y1) * (1.0 - fx) + v(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// A terrain the simulator can hop on.
#[derive(Clone, Debug, PartialEq)]
pub enum Terrain {
    Wood(WoodParams),
    Carpet(CarpetParams),
    Clay(ClayParams),
    Grass(GrassParams),
    Image {
        map: HeightMap,
        params: ImageTerrainParams,
    },
}

/// Deterministic hash of integers to a uniform number in `[0, 1)` (SplitMix64 finaliser).
pub(crate) fn hash_unit(seed: u64, a: i64, b: i64, c: u64) -> f64 {
    let mut z = seed
        ^ (a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (b as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ c.wrapping_mul(0x1656_67B1_9E37_79F9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// Value noise in `[-1, 1]` on a square lattice of spacing 1, bilinearly interpolated with smoothstep.
fn value_noise(seed: u64, u: f64, v: f64) -> f64 {
    let (i, j) = (u.floor(), v.floor());
    let (fu, fv) = (u - i, v - j);
    let (su, sv) = (fu * fu * (3.0 - 2.0 * fu), fv * fv * (3.0 - 2.0 * fv));
    let (i, j) = (i as i64, j as i64);
    let n = |a: i64, b: i64| 2.0 * hash_unit(seed, a, b, 7) - 1.0;
    let top = n(i, j) * (1.0 - su) + n(i + 1, j) * su;
    let bottom = n(i, j + 1) * (1.0 - su) + n(i + 1, j + 1) * su;
    top * (1.0 - sv) + bottom * sv
}

/// A log-normal factor `exp(N(0, sd))`, 1 when `sd == 0`.
fn jitter<R: Rng + ?Sized>(rng: &mut R, sd: f64) -> f64 {
    if sd <= 0.0 {
        return 1.0;
    }
    Normal::new(0.0, sd).map_or(1.0, |n| n.sample(rng).exp())
}

fn uniform<R: Rng + ?Sized>(rng: &mut R, range: [f64; 2]) -> f64 {
    if range[1] > range[0] {
        rng.random_range(range[0]..range[1])
    } else {
        range[0]
    }
}

impl Terrain {
    /// The terrain's macroscopic normal compliance for the dynamics.
    pub fn ground(&self) -> GroundParams {
        match self {
            Self::Wood(p) => p.ground,
            Self::Carpet(p) => p.ground,
            Self::Clay(p) => p.ground,
            Self::Grass(p) => p.ground,
            Self::Image { params, .. } => params.ground,
        }
    }

    pub fn validate(&self, name: &str) -> Result<()> {
        self.ground().validate(&format!("terrains.{name}.ground"))
    }

    /// A new random patch of this terrain under the foot's sample points `(x, y)` (m, foot frame).
    /// `variability` scales the hop-to-hop variation of the terrain's dimensions (0: none, 1: default).
    pub fn patch<R: Rng + ?Sized>(
        &self,
        points: &[(f64, f64)],
        rng: &mut R,
        variability: f64,
    ) -> SurfacePatch {
        let n = points.len();
        let mut out = SurfacePatch {
            height_m: vec![0.0; n],
            stiffness_pa_per_m: vec![f64::INFINITY; n],
            yield_pa: vec![f64::INFINITY; n],
        };
        let frame = PatchFrame::draw(rng, variability);
        match self {
            Self::Wood(p) => wood_patch(p, points, rng, &frame, &mut out),
            Self::Carpet(p) => carpet_patch(p, points, rng, &frame, &mut out),
            Self::Clay(p) => clay_patch(p, points, rng, &frame, &mut out),
            Self::Grass(p) => grass_patch(p, points, rng, &frame, &mut out),
            Self::Image { map, params } => image_patch(map, params, points, rng, &frame, &mut out),
        }
        out
    }
}

/// What every terrain's patch draws first: the terrain's yaw under the foot, the noise seed, and the
/// spreads of the hop-to-hop variation of its dimensions.
struct PatchFrame {
    sin_yaw: f64,
    cos_yaw: f64,
    seed: u64,
    variability: f64,
    size_sd: f64,
    relief_sd: f64,
}

impl PatchFrame {
    /// Draws the yaw, then the seed (this order is part of the seeded outputs).
    fn draw<R: Rng + ?Sized>(rng: &mut R, variability: f64) -> Self {
        let yaw: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let (sin_yaw, cos_yaw) = yaw.sin_cos();
        let seed: u64 = rng.random();
        Self {
            sin_yaw,
            cos_yaw,
            seed,
            variability,
            size_sd: 0.08 * variability,
            relief_sd: 0.2 * variability,
        }
    }

    /// A foot-frame point in the terrain's frame.
    fn rotate(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.cos_yaw * x - self.sin_yaw * y,
            self.sin_yaw * x + self.cos_yaw * y,
        )
    }
}

/// Wood: growth rings along the grain (latewood ridges), fine roughness, planks with steps and seams.
fn wood_patch<R: Rng + ?Sized>(
    p: &WoodParams,
    points: &[(f64, f64)],
    rng: &mut R,
    frame: &PatchFrame,
    out: &mut SurfacePatch,
) {
    let seed = frame.seed;
    let spacing = p.ring_spacing_m * jitter(rng, frame.size_sd);
    let relief = p.grain_relief_m * jitter(rng, frame.relief_sd);
    let wave_phase = rng.random_range(0.0..std::f64::consts::TAU);
    let wave = p.grain_waviness_m * jitter(rng, frame.relief_sd);
    // Across-grain coordinate of the foot centre inside its plank.
    let plank_offset = rng.random_range(0.0..p.plank_width_m);
    let step_sd = p.plank_step_sd_m * frame.variability.max(1e-9);
    let step = Normal::new(0.0, step_sd).map_or(0.0, |d| d.sample(rng));
    let ring_offset = rng.random_range(0.0..spacing);
    for (i, &(x, y)) in points.iter().enumerate() {
        // u along the grain, v across it.
        let (u, v) = frame.rotate(x, y);
        let v_w = v
            + wave * (std::f64::consts::TAU * u / p.grain_waviness_wavelength_m + wave_phase).sin()
            + ring_offset;
        let ring = (v_w / spacing).floor();
        // Ring-to-ring variation of spacing and relief.
        let ring_relief = relief * (0.6 + 0.8 * hash_unit(seed, ring as i64, 0, 1));
        let frac = v_w / spacing - ring;
        let lw = p.latewood_fraction;
        let grain = if frac < lw {
            ring_relief * (std::f64::consts::PI * frac / lw).sin().powi(2)
        } else {
            0.0
        };
        let rough = p.roughness_m * value_noise(seed ^ 0x55, x / 0.5e-3, y / 0.5e-3);
        // Plank index across the grain and the seams between planks.
        let across = v + plank_offset;
        let plank = (across / p.plank_width_m).floor();
        let in_plank = across - plank * p.plank_width_m;
        let mut h = grain + rough + if plank as i64 % 2 == 0 { 0.0 } else { step };
        if in_plank < p.seam_gap_m {
            h -= 2e-3;
        }
        out.height_m[i] = h;
        out.stiffness_pa_per_m[i] = p.surface_stiffness_pa_per_m;
    }
}

/// The loops of one carpet patch: the lattice (stitch along, gauge across), its offset, and the spreads.
struct CarpetLoops {
    stitch: f64,
    gauge: f64,
    height_sd: f64,
    position_sd: f64,
}

/// Carpet: a lattice of elliptic loops, each jittered in place and height; between them, the pile.
fn carpet_patch<R: Rng + ?Sized>(
    p: &CarpetParams,
    points: &[(f64, f64)],
    rng: &mut R,
    frame: &PatchFrame,
    out: &mut SurfacePatch,
) {
    let scale = jitter(rng, frame.size_sd * 0.5);
    let (stitch, gauge) = (p.stitch_m * scale, p.gauge_m * scale);
    let (off_u, off_v) = (rng.random_range(0.0..stitch), rng.random_range(0.0..gauge));
    let loops = CarpetLoops {
        stitch,
        gauge,
        height_sd: p.loop_height_sd_m * jitter(rng, frame.relief_sd),
        position_sd: p.loop_position_sd_m * frame.variability,
    };
    for (i, &(x, y)) in points.iter().enumerate() {
        let (u, v) = frame.rotate(x, y);
        out.height_m[i] = carpet_height_at(p, &loops, frame.seed, u + off_u, v + off_v);
        out.stiffness_pa_per_m[i] = p.loop_stiffness_pa_per_m;
    }
}

/// The carpet's top at `(u, v)` (terrain frame, lattice offset added): the highest of the nine nearest
/// loops, or the pile's depth where no loop covers the point.
fn carpet_height_at(p: &CarpetParams, loops: &CarpetLoops, seed: u64, u: f64, v: f64) -> f64 {
    let (stitch, gauge, pos_sd) = (loops.stitch, loops.gauge, loops.position_sd);
    let (ci, cj) = ((u / stitch).round() as i64, (v / gauge).round() as i64);
    let mut best = -p.pile_depth_m;
    for di in -1..=1 {
        for dj in -1..=1 {
            let (a, b) = (ci + di, cj + dj);
            let gauss = |k: u64| {
                // Sum of uniforms: approximately normal, unit variance.
                (hash_unit(seed, a, b, k)
                    + hash_unit(seed, a, b, k + 1)
                    + hash_unit(seed, a, b, k + 2)
                    - 1.5)
                    * 2.0
            };
            let cu = a as f64 * stitch + pos_sd * gauss(10);
            let cv = b as f64 * gauge + pos_sd * gauss(20);
            let q = ((u - cu) / (0.5 * p.loop_length_m)).powi(2)
                + ((v - cv) / (0.5 * p.loop_width_m)).powi(2);
            if q < 1.0 {
                let top = loops.height_sd * gauss(30);
                best = best.max(top - p.loop_crown_m * q);
            }
        }
    }
    best
}

/// Clay: undulating soil with grit that yields, and stiff clumps lying on it.
fn clay_patch<R: Rng + ?Sized>(
    p: &ClayParams,
    points: &[(f64, f64)],
    rng: &mut R,
    frame: &PatchFrame,
    out: &mut SurfacePatch,
) {
    let waves = draw_clay_waves(p, rng, frame);
    let clumps = draw_clay_clumps(p, rng, frame);
    for (i, &(x, y)) in points.iter().enumerate() {
        let (u, v) = frame.rotate(x, y);
        let mut h: f64 = waves
            .iter()
            .map(|&(kx, ky, ph, a)| a * (kx * u + ky * v + ph).sin())
            .sum();
        h += p.grit_m * value_noise(frame.seed, u / p.grit_length_m, v / p.grit_length_m);
        let mut clump_h = 0.0_f64;
        for &(cx, cy, r, ch, el) in &clumps {
            let q = ((x - cx) / r).powi(2) + ((y - cy) / (r * el)).powi(2);
            if q < 1.0 {
                clump_h = clump_h.max(ch * (1.0 - q).sqrt());
            }
        }
        out.height_m[i] = h + clump_h;
        if clump_h > 0.0 {
            out.stiffness_pa_per_m[i] = p.clump_stiffness_pa_per_m;
        } else {
            out.stiffness_pa_per_m[i] = p.soil_stiffness_pa_per_m;
            out.yield_pa[i] = p.soil_yield_pa;
        }
    }
}

/// Four plane waves of the clay's undulation: wave vector `(kx, ky)`, phase, amplitude.
fn draw_clay_waves<R: Rng + ?Sized>(
    p: &ClayParams,
    rng: &mut R,
    frame: &PatchFrame,
) -> Vec<(f64, f64, f64, f64)> {
    let und = p.undulation_m * jitter(rng, frame.relief_sd);
    (0..4)
        .map(|_| {
            let dir: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let wl = p.undulation_wavelength_m * rng.random_range(1.0..2.5);
            let k = std::f64::consts::TAU / wl;
            (
                k * dir.cos(),
                k * dir.sin(),
                rng.random_range(0.0..6.3),
                und * 0.5,
            )
        })
        .collect()
}

/// The clay's clumps (foot frame): centre, radius, height, elongation; a Poisson number of them.
fn draw_clay_clumps<R: Rng + ?Sized>(
    p: &ClayParams,
    rng: &mut R,
    frame: &PatchFrame,
) -> Vec<(f64, f64, f64, f64, f64)> {
    // Clumps over a square twice the foot's size.
    let half = 0.05;
    let density = p.clumps_per_m2 * jitter(rng, frame.relief_sd);
    let expected = density * (2.0 * half) * (2.0 * half);
    let count =
        rand_distr::Poisson::new(expected.max(1e-9)).map_or(0.0, |d| d.sample(rng)) as usize;
    (0..count)
        .map(|_| {
            let cx = rng.random_range(-half..half);
            let cy = rng.random_range(-half..half);
            let r = uniform(rng, p.clump_radius_m);
            let h = uniform(rng, p.clump_height_m);
            let elong = rng.random_range(0.6..1.0);
            (cx, cy, r, h, elong)
        })
        .collect()
}

/// Half the side of the square (foot frame) grass blades and stems are scattered over.
const GRASS_HALF_SIDE_M: f64 = 0.045;

/// Grass: layers of blades lying roughly one way, stems under them, soil below a gap.
fn grass_patch<R: Rng + ?Sized>(
    p: &GrassParams,
    points: &[(f64, f64)],
    rng: &mut R,
    frame: &PatchFrame,
    out: &mut SurfacePatch,
) {
    let (blades, stems) = draw_grass(p, rng, frame);
    for (i, &(x, y)) in points.iter().enumerate() {
        let top = grass_blade_stack_at(&blades, x, y).max(grass_stem_top_at(p, &stems, x, y));
        if top > 0.0 {
            out.height_m[i] = top;
            out.stiffness_pa_per_m[i] = p.blade_stiffness_pa_per_m;
        } else {
            out.height_m[i] = -p.soil_gap_m;
            out.stiffness_pa_per_m[i] = p.soil_stiffness_pa_per_m;
        }
    }
}

/// The grass's blades (centre, unit direction, half length, half width, thickness, lift) and stems
/// (centre, unit direction, half length), both in the foot frame, drawn in that order.
#[allow(clippy::type_complexity)]
fn draw_grass<R: Rng + ?Sized>(
    p: &GrassParams,
    rng: &mut R,
    frame: &PatchFrame,
) -> (Vec<[f64; 8]>, Vec<[f64; 5]>) {
    let half = GRASS_HALF_SIDE_M;
    let area = (2.0 * half) * (2.0 * half);
    let mean_w = 0.5 * (p.blade_width_m[0] + p.blade_width_m[1]);
    let mean_l = 0.5 * (p.blade_length_m[0] + p.blade_length_m[1]);
    let layers = p.blade_layers * jitter(rng, frame.relief_sd * 0.5);
    let expected = layers * area / (mean_w * mean_l) * 2.0;
    let count =
        rand_distr::Poisson::new(expected.max(1e-9)).map_or(0.0, |d| d.sample(rng)) as usize;
    let lay: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let dir_sd = Normal::new(0.0, p.blade_direction_sd_rad.max(1e-9)).ok();
    let blades: Vec<[f64; 8]> = (0..count)
        .map(|_| {
            let cx = rng.random_range(-half..half);
            let cy = rng.random_range(-half..half);
            let a = lay + dir_sd.as_ref().map_or(0.0, |d| d.sample(rng));
            let l = uniform(rng, p.blade_length_m);
            let w = uniform(rng, p.blade_width_m);
            let t = p.blade_thickness_m * rng.random_range(0.7..1.3);
            let curl = rng.random_range(0.0..0.4e-3);
            [cx, cy, a.cos(), a.sin(), 0.5 * l, 0.5 * w, t, curl]
        })
        .collect();
    let stems_expected = p.stems_per_m2 * area;
    let stem_count =
        rand_distr::Poisson::new(stems_expected.max(1e-9)).map_or(0.0, |d| d.sample(rng)) as usize;
    let stems: Vec<[f64; 5]> = (0..stem_count)
        .map(|_| {
            let cx = rng.random_range(-half..half);
            let cy = rng.random_range(-half..half);
            let a = lay + dir_sd.as_ref().map_or(0.0, |d| 0.5 * d.sample(rng));
            let l = uniform(rng, p.blade_length_m);
            [cx, cy, a.cos(), a.sin(), 0.5 * l]
        })
        .collect();
    (blades, stems)
}

/// The height of the blades stacked over `(x, y)` (0 where none lies).
fn grass_blade_stack_at(blades: &[[f64; 8]], x: f64, y: f64) -> f64 {
    let mut stack = 0.0;
    for b in blades {
        let (dx, dy) = (x - b[0], y - b[1]);
        let along = dx * b[2] + dy * b[3];
        let across = -dx * b[3] + dy * b[2];
        if along.abs() < b[4] && across.abs() < b[5] {
            // Blades are folded along the midrib: thickest in the middle.
            let profile = 1.0 - 0.5 * (across / b[5]).powi(2);
            // A blade arches over what lies below it (curl along its length).
            let arch = b[7] * (1.0 - (along / b[4]).powi(2));
            stack += b[6] * profile + arch * 0.3;
        }
    }
    stack
}

/// The top of the highest stem (a lying cylinder) over `(x, y)` (0 where none lies).
fn grass_stem_top_at(p: &GrassParams, stems: &[[f64; 5]], x: f64, y: f64) -> f64 {
    let mut stem = 0.0_f64;
    let r = 0.5 * p.stem_diameter_m;
    for s in stems {
        let (dx, dy) = (x - s[0], y - s[1]);
        let along = dx * s[2] + dy * s[3];
        let across = -dx * s[3] + dy * s[2];
        if along.abs() < s[4] && across.abs() < r {
            stem = stem.max(r + (r * r - across * across).sqrt());
        }
    }
    stem
}

/// An image terrain: the height map at a random offset and scale, one stiffness everywhere.
fn image_patch<R: Rng + ?Sized>(
    map: &HeightMap,
    params: &ImageTerrainParams,
    points: &[(f64, f64)],
    rng: &mut R,
    frame: &PatchFrame,
    out: &mut SurfacePatch,
) {
    let px = params.pixel_size_m * jitter(rng, frame.size_sd * 0.5);
    let relief = params.relief_m * jitter(rng, frame.relief_sd);
    let ox = rng.random_range(0.0..map.width as f64);
    let oy = rng.random_range(0.0..map.height as f64);
    for (i, &(x, y)) in points.iter().enumerate() {
        let (u, v) = frame.rotate(x, y);
        let value = map.sample(ox + u / px, oy - v / px);
        out.height_m[i] = relief * value;
        out.stiffness_pa_per_m[i] = params.surface_stiffness_pa_per_m;
    }
}
