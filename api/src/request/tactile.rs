//! A tactile session request in domain terms, as both transports produce it.

use graspd_core::tactile::{LayoutSpec, StabilizerConfig, TareConfig};

/// A finger's sensor layout as the transports receive it.
#[derive(Debug, Clone, PartialEq)]
pub enum LayoutChoice {
    /// A built-in layout (`biotac`, `biotac_sp`).
    Name(String),
    /// Electrode coordinates, validated like the data files.
    Custom(LayoutSpec),
}

/// One finger of a session request.
#[derive(Debug, Clone, PartialEq)]
pub struct TactileFingerRequest {
    pub name: String,
    pub layout: LayoutChoice,
    pub tare: TareConfig,
    /// The sensor gives only its electrodes (`FingerConfig::electrodes_only`).
    pub electrodes_only: bool,
    /// The calibration this finger detects with, whatever the session's detector.
    pub calibration: Option<String>,
}

/// A session request in domain terms, as both transports produce it: `config` holds every
/// parameter except the fingers, whose layouts the facade resolves.
#[derive(Debug, Clone, PartialEq)]
pub struct TactileSessionRequest {
    pub fingers: Vec<TactileFingerRequest>,
    pub config: StabilizerConfig,
}
