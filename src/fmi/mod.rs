//! FMI 2.0 co-simulation support, in safe Rust: the variable table, the instance state
//! machine, FMU-state snapshots, modelDescription.xml, documentation and packaging.
//! The `extern "C"` functions live in the `fmu/` crate and only call into this module.

mod access;
pub mod dependencies;
#[cfg(feature = "cli")]
pub mod description;
#[cfg(feature = "cli")]
pub mod documentation;
pub mod instance;
#[cfg(feature = "cli")]
pub mod package;
mod parameters;
#[cfg(feature = "cli")]
pub mod platforms;
pub mod snapshot;
mod state;
pub mod variables;

use sha2::{Digest, Sha256};

pub use instance::{FmiError, FmiResult, Instance};

/// Hash of the sources of the FMU binary (see `build.rs`).
pub const BUILD_ID: &str = env!("TENSEGRITY_BUILD_ID");

/// The instance modes of the FMI 2.0 co-simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// After `fmi2Instantiate` (and `fmi2Reset`).
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// After `fmi2Terminate`.
    Terminated,
    /// After a call returned `fmi2Error`: only reset, restore or free.
    Error,
}

/// Statuses a call can report (mapped to `fmi2Status` by the C layer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `fmi2OK`.
    Ok,
    /// `fmi2Warning`.
    Warning,
    /// `fmi2Discard`.
    Discard,
    /// `fmi2Error`.
    Error,
}

/// Log categories declared in modelDescription.xml.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Category {
    /// Informational messages.
    Events = 0,
    /// Warnings (clamped inputs, projected velocities, skipped bars).
    Warning = 1,
    /// Errors (illegal calls, bad values, numerical failures).
    Error = 2,
}

impl Category {
    /// Every category, in declaration order.
    pub const ALL: [Category; 3] = [Category::Events, Category::Warning, Category::Error];

    /// The declared name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Events => "logEvents",
            Self::Warning => "logStatusWarning",
            Self::Error => "logStatusError",
        }
    }

    /// What the category holds.
    pub fn description(self) -> &'static str {
        match self {
            Self::Events => "informational messages",
            Self::Warning => "warnings: clamped inputs, projected velocities, skipped bars",
            Self::Error => "errors: illegal call sequences, rejected values, numerical failures",
        }
    }

    /// Looks a category up by its declared name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// A message for the importer's logger.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Its category.
    pub category: Category,
    /// The text (not yet escaped for printf).
    pub text: String,
}

/// The GUID of an FMU: a hash of the binary's build id and the scene text.
pub fn guid_for(scene_text: &str) -> String {
    let mut hasher = Sha256::new();
    hasher.update(BUILD_ID.as_bytes());
    hasher.update([0u8]);
    hasher.update(scene_text.as_bytes());
    let d = hasher.finalize();
    let hex: String = d.iter().take(16).map(|b| format!("{b:02x}")).collect();
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

/// The folder named by `fmuResourceLocation`: a `file:` URI (`file:///…` percent-encoded,
/// or `file:/…`), or a plain path as some importers pass.
pub fn resource_path(location: &str) -> Result<std::path::PathBuf, String> {
    if !location.starts_with("file:") {
        return Ok(std::path::PathBuf::from(location));
    }
    let url = url::Url::parse(location)
        .map_err(|e| format!("fmuResourceLocation '{location}' is not a valid URI: {e}"))?;
    url.to_file_path()
        .map_err(|()| format!("fmuResourceLocation '{location}' is not a local file URI"))
}
