//! A tactile session request in domain terms, as both transports produce it.

use graspd_core::tactile::{DesiredForceLaw, LayoutSpec, StabilizerConfig, TareConfig};

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

/// The desired-force law's fields as either transport sends them (Eq 6.9; unset: the default).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LawWire {
    pub f0: Option<f64>,
    pub delta_material: Option<f64>,
    pub delta_slip: Option<f64>,
    pub f_min: Option<f64>,
    pub f_max: Option<f64>,
    pub latch_slip: Option<bool>,
}

impl LawWire {
    /// The law, each unset field at [`DesiredForceLaw::default`]'s value (the stabilizer
    /// checks the ranges).
    pub fn law(self) -> DesiredForceLaw {
        let d = DesiredForceLaw::default();
        DesiredForceLaw {
            f0: self.f0.unwrap_or(d.f0),
            delta_material: self.delta_material.unwrap_or(d.delta_material),
            delta_slip: self.delta_slip.unwrap_or(d.delta_slip),
            f_min: self.f_min.unwrap_or(d.f_min),
            f_max: self.f_max.unwrap_or(d.f_max),
            latch_slip: self.latch_slip.unwrap_or(d.latch_slip),
        }
    }
}
