//! The one error type of the node.

/// What can go wrong setting up or running the node.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Ros2Error {
    /// A node name, namespace or topic name that breaks ROS 2's naming rules.
    #[error("invalid {what} {name:?}: {why}")]
    Name {
        what: &'static str,
        name: String,
        why: String,
    },
    /// A domain id outside ROS 2's range.
    #[error(
        "invalid ROS 2 domain id {value} (from {source_name}): ROS 2 domain ids are 0 to {max}; set \
         ROS_DOMAIN_ID or the node's domain id to one in that range"
    )]
    DomainId {
        value: String,
        source_name: &'static str,
        max: u16,
    },
    /// A setting that cannot be used (a QoS depth of 0, an unknown input type).
    #[error("{0}")]
    Setting(String),
    /// The DDS middleware failed (creating the participant, a topic, a reader or a writer).
    #[error("ROS 2 (DDS): cannot {action}: {detail}")]
    Dds { action: String, detail: String },
    /// The library failed (the model, the profile, the session).
    #[error(transparent)]
    Presrs(#[from] presrs::Error),
}

impl Ros2Error {
    /// A DDS failure while doing `action`.
    pub fn dds(action: impl Into<String>, detail: impl std::fmt::Debug) -> Self {
        Self::Dds {
            action: action.into(),
            detail: format!("{detail:?}"),
        }
    }
}

/// The node's results.
pub type Result<T, E = Ros2Error> = std::result::Result<T, E>;
