//! Tactile sessions, frames and stabilization setpoints (the Stabilize stream).

use crate::request::{LawWire, LayoutChoice, TactileFingerRequest, TactileSessionRequest};
use graspd_core::FieldError;
use graspd_core::tactile::{
    Baseline, ContactEvent, ControlMode, DetectorChoice, ElectrodePolarity, FingerReading,
    FingerResult, ForceUnit, Frame, FrameResult, LayoutSpec, Material, ModelFreeThresholds,
    PidGains, SlipDirection, StabilizerConfig, TareConfig,
};
use graspd_proto::v1 as pb;
use graspd_proto::v1::stabilize_request::Kind;
use graspd_proto::v1::tactile_detector::Kind as DetectorKind;
use graspd_proto::v1::tactile_finger::Layout as FingerLayout;

/// The first message of a `Stabilize` stream: it must open the session.
pub fn stabilize_session_from_proto(
    m: pb::StabilizeRequest,
) -> Result<TactileSessionRequest, FieldError> {
    match m.kind {
        Some(Kind::Session(s)) => tactile_session_from_proto(s),
        Some(Kind::Frame(_)) => Err(FieldError::new(
            "session",
            "the first message must open the session (set `session`); frames follow it",
        )),
        None => Err(FieldError::new(
            "session",
            "is required in the first message",
        )),
    }
}

/// A later message of a `Stabilize` stream: it must carry a frame.
pub fn stabilize_frame_from_proto(m: pb::StabilizeRequest) -> Result<Frame, FieldError> {
    match m.kind {
        Some(Kind::Frame(f)) => Ok(tactile_frame_from_proto(f)),
        Some(Kind::Session(_)) => Err(FieldError::new(
            "session",
            "the session is already open; every later message carries a `frame`",
        )),
        None => Err(FieldError::new("frame", "is required")),
    }
}

fn usize_or(v: Option<u32>, default: usize) -> usize {
    v.map_or(default, |v| v as usize)
}

pub fn tactile_session_from_proto(
    s: pb::TactileSession,
) -> Result<TactileSessionRequest, FieldError> {
    let d = StabilizerConfig::default();
    let fingers = s
        .fingers
        .into_iter()
        .enumerate()
        .map(|(i, f)| {
            let layout = match f.layout {
                Some(FingerLayout::LayoutName(n)) => LayoutChoice::Name(n),
                Some(FingerLayout::CustomLayout(c)) => LayoutChoice::Custom(LayoutSpec {
                    name: c.name,
                    description: String::new(),
                    electrodes: c.electrodes.iter().map(|e| [e.x_mm, e.y_mm]).collect(),
                }),
                None => {
                    return Err(FieldError::new(
                        format!("session.fingers[{i}].layout"),
                        "is required: a layout_name (biotac, biotac_sp) or a custom_layout",
                    ));
                }
            };
            let tare = tare_from_proto(f.tare, &format!("session.fingers[{i}].tare"))?;
            Ok(TactileFingerRequest {
                name: f.name,
                layout,
                tare,
                electrodes_only: f.electrodes_only,
                calibration: f.calibration,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    let p = s.pid.unwrap_or_default();
    let pd = d.pid;
    let detector = match s.detector.and_then(|d| d.kind) {
        None => d.detector.clone(),
        Some(DetectorKind::Model(name)) => DetectorChoice::Model(name),
        Some(DetectorKind::Calibration(name)) => DetectorChoice::Calibration(name),
        Some(DetectorKind::ModelFree(t)) => {
            let td = ModelFreeThresholds::default();
            DetectorChoice::ModelFree(ModelFreeThresholds {
                pdc_contact: t.pdc_contact.unwrap_or(td.pdc_contact),
                electrode_contact: t.electrode_contact.unwrap_or(td.electrode_contact),
                slip_vibration: t.slip_vibration.unwrap_or(td.slip_vibration),
                steepness: t.steepness.unwrap_or(td.steepness),
            })
        }
    };
    Ok(TactileSessionRequest {
        fingers,
        config: StabilizerConfig {
            fingers: Vec::new(),
            window_length: usize_or(s.window_length, d.window_length),
            stride: usize_or(s.stride, d.stride),
            law: LawWire {
                f0: s.f0,
                delta_material: s.delta_material,
                delta_slip: s.delta_slip,
                f_min: s.f_min,
                f_max: s.f_max,
                latch_slip: s.latch_slip,
            }
            .law(),
            pid: PidGains {
                kp: p.kp.unwrap_or(pd.kp),
                ki: p.ki.unwrap_or(pd.ki),
                kd: p.kd.unwrap_or(pd.kd),
                output_min: p.output_min.unwrap_or(pd.output_min),
                output_max: p.output_max.unwrap_or(pd.output_max),
                derivative_filter_s: p.derivative_filter_s.unwrap_or(pd.derivative_filter_s),
            },
            alpha: s.alpha.unwrap_or(d.alpha),
            calibration_gain: s.calibration_gain,
            detector,
            centroid_slip_mm_s: s.centroid_slip_mm_s,
        },
    })
}

pub fn tare_from_proto(t: Option<pb::TareSettings>, field: &str) -> Result<TareConfig, FieldError> {
    let Some(t) = t else {
        return Ok(TareConfig::default());
    };
    let polarity = pb::ElectrodePolarity::try_from(t.electrode_polarity).map_err(|_| {
        FieldError::new(
            format!("{field}.electrode_polarity"),
            format!("unknown value {}", t.electrode_polarity),
        )
    })?;
    let electrode_polarity = match polarity {
        pb::ElectrodePolarity::Falling => ElectrodePolarity::Falling,
        pb::ElectrodePolarity::Rising => ElectrodePolarity::Rising,
        pb::ElectrodePolarity::Unspecified if t.pretared => ElectrodePolarity::Rising,
        pb::ElectrodePolarity::Unspecified => ElectrodePolarity::Falling,
    };
    let baseline = if t.pretared {
        Baseline::None
    } else {
        match TareConfig::default().baseline {
            Baseline::FirstFrames(n) => Baseline::FirstFrames(usize_or(t.baseline_frames, n)),
            Baseline::None => Baseline::None,
        }
    };
    Ok(TareConfig {
        baseline,
        electrode_polarity,
    })
}

/// Taring as the proto's TareSettings (the inverse of [`tare_from_proto`]).
pub(super) fn tare_to_proto(t: &TareConfig) -> pb::TareSettings {
    pb::TareSettings {
        baseline_frames: match t.baseline {
            Baseline::FirstFrames(n) => Some(n.min(u32::MAX as usize) as u32),
            Baseline::None => None,
        },
        pretared: t.baseline == Baseline::None,
        electrode_polarity: match t.electrode_polarity {
            ElectrodePolarity::Falling => pb::ElectrodePolarity::Falling,
            ElectrodePolarity::Rising => pb::ElectrodePolarity::Rising,
        } as i32,
    }
}

/// The client's side: a session request as the proto message.
pub fn tactile_session_to_proto(r: &TactileSessionRequest) -> pb::TactileSession {
    let c = &r.config;
    pb::TactileSession {
        fingers: r
            .fingers
            .iter()
            .map(|f| pb::TactileFinger {
                name: f.name.clone(),
                layout: Some(match &f.layout {
                    LayoutChoice::Name(n) => FingerLayout::LayoutName(n.clone()),
                    LayoutChoice::Custom(spec) => FingerLayout::CustomLayout(pb::CustomLayout {
                        name: spec.name.clone(),
                        electrodes: spec
                            .electrodes
                            .iter()
                            .map(|e| pb::Electrode {
                                x_mm: e[0],
                                y_mm: e[1],
                            })
                            .collect(),
                    }),
                }),
                tare: Some(tare_to_proto(&f.tare)),
                electrodes_only: f.electrodes_only,
                calibration: f.calibration.clone(),
            })
            .collect(),
        window_length: Some(c.window_length.min(u32::MAX as usize) as u32),
        stride: Some(c.stride.min(u32::MAX as usize) as u32),
        f0: Some(c.law.f0),
        delta_material: Some(c.law.delta_material),
        delta_slip: Some(c.law.delta_slip),
        f_min: Some(c.law.f_min),
        f_max: Some(c.law.f_max),
        latch_slip: Some(c.law.latch_slip),
        centroid_slip_mm_s: c.centroid_slip_mm_s,
        pid: Some(pb::PidGains {
            kp: Some(c.pid.kp),
            ki: Some(c.pid.ki),
            kd: Some(c.pid.kd),
            output_min: Some(c.pid.output_min),
            output_max: Some(c.pid.output_max),
            derivative_filter_s: Some(c.pid.derivative_filter_s),
        }),
        alpha: Some(c.alpha),
        calibration_gain: c.calibration_gain,
        // Default: unset, so that the server chooses (its model when one is loaded).
        detector: match &c.detector {
            DetectorChoice::Default => None,
            DetectorChoice::Model(n) => Some(pb::TactileDetector {
                kind: Some(DetectorKind::Model(n.clone())),
            }),
            DetectorChoice::Calibration(n) => Some(pb::TactileDetector {
                kind: Some(DetectorKind::Calibration(n.clone())),
            }),
            DetectorChoice::ModelFree(t) => Some(pb::TactileDetector {
                kind: Some(DetectorKind::ModelFree(pb::ModelFreeThresholds {
                    pdc_contact: Some(t.pdc_contact),
                    electrode_contact: Some(t.electrode_contact),
                    slip_vibration: Some(t.slip_vibration),
                    steepness: Some(t.steepness),
                })),
            }),
        },
    }
}

/// A frame as received; the session validates it (counts, order, finite values).
pub fn tactile_frame_from_proto(f: pb::TactileFrame) -> Frame {
    Frame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .into_iter()
            .map(|r| FingerReading {
                pdc: r.pdc,
                pac: r.pac,
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes,
            })
            .collect(),
    }
}

pub fn tactile_frame_to_proto(f: &Frame) -> pb::TactileFrame {
    pb::TactileFrame {
        timestamp: f.timestamp,
        fingers: f
            .fingers
            .iter()
            .map(|r| pb::FingerReading {
                pdc: r.pdc,
                pac: r.pac.clone(),
                tdc: r.tdc,
                tac: r.tac,
                electrodes: r.electrodes.clone(),
            })
            .collect(),
    }
}

/// The answer to frame number `index` (0-based) of a session.
pub fn setpoint_to_proto(r: &FrameResult, index: u64) -> pb::StabilizationSetpoint {
    pb::StabilizationSetpoint {
        timestamp: r.timestamp,
        frame_index: index,
        fingers: r
            .fingers
            .iter()
            .map(|f| pb::FingerSetpoint {
                finger: f.finger.clone(),
                tared: f.tared,
                event: match f.event {
                    ContactEvent::NonContact => pb::ContactEvent::NonContact,
                    ContactEvent::Contact => pb::ContactEvent::Contact,
                    ContactEvent::Slip => pb::ContactEvent::Slip,
                } as i32,
                event_probabilities: f.event_probabilities.to_vec(),
                material: match f.material {
                    Material::Unknown => pb::Material::Unknown,
                    Material::Paper => pb::Material::Paper,
                    Material::Foam => pb::Material::Foam,
                    Material::Plastic => pb::Material::Plastic,
                    Material::Metal => pb::Material::Metal,
                } as i32,
                material_probabilities: f
                    .material_probabilities
                    .map(|p| p.to_vec())
                    .unwrap_or_default(),
                slip_direction: f.slip_direction.map_or(
                    pb::SlipDirection::Unspecified as i32,
                    slip_direction_to_proto,
                ),
                slip_direction_probabilities: f
                    .slip_direction_probabilities
                    .map(|p| p.to_vec())
                    .unwrap_or_default(),
                force: f.force,
                force_unit: match f.force_unit {
                    ForceUnit::Raw => pb::ForceUnit::Raw,
                    ForceUnit::Newton => pb::ForceUnit::Newton,
                } as i32,
                contact_location: f.contact_location.map(|l| pb::ImageLocation {
                    row: l[0],
                    col: l[1],
                }),
                contact_area_pixels: f.contact_area_pixels.min(u32::MAX as usize) as u32,
                contact_area_mm2: f.contact_area_mm2,
                desired_force: f.desired_force,
                mode: match f.mode {
                    ControlMode::Position => pb::ControlMode::Position,
                    ControlMode::Force => pb::ControlMode::Force,
                } as i32,
                setpoint: f.setpoint,
            })
            .collect(),
    }
}

/// The client's side: a setpoint message as the domain result (errors name the field).
pub fn setpoint_from_proto(m: pb::StabilizationSetpoint) -> Result<FrameResult, FieldError> {
    let fingers = m
        .fingers
        .into_iter()
        .enumerate()
        .map(|(i, f)| {
            let field = |name: &str| format!("fingers[{i}].{name}");
            let event = match pb::ContactEvent::try_from(f.event) {
                Ok(pb::ContactEvent::NonContact) => ContactEvent::NonContact,
                Ok(pb::ContactEvent::Contact) => ContactEvent::Contact,
                Ok(pb::ContactEvent::Slip) => ContactEvent::Slip,
                _ => {
                    return Err(FieldError::new(
                        field("event"),
                        format!("unknown value {}", f.event),
                    ));
                }
            };
            let material = match pb::Material::try_from(f.material) {
                Ok(pb::Material::Unknown) => Material::Unknown,
                Ok(pb::Material::Paper) => Material::Paper,
                Ok(pb::Material::Foam) => Material::Foam,
                Ok(pb::Material::Plastic) => Material::Plastic,
                Ok(pb::Material::Metal) => Material::Metal,
                _ => {
                    return Err(FieldError::new(
                        field("material"),
                        format!("unknown value {}", f.material),
                    ));
                }
            };
            let mode = match pb::ControlMode::try_from(f.mode) {
                Ok(pb::ControlMode::Position) => ControlMode::Position,
                Ok(pb::ControlMode::Force) => ControlMode::Force,
                _ => {
                    return Err(FieldError::new(
                        field("mode"),
                        format!("unknown value {}", f.mode),
                    ));
                }
            };
            let force_unit = match pb::ForceUnit::try_from(f.force_unit) {
                Ok(pb::ForceUnit::Newton) => ForceUnit::Newton,
                Ok(pb::ForceUnit::Raw) => ForceUnit::Raw,
                _ => {
                    return Err(FieldError::new(
                        field("force_unit"),
                        format!("unknown value {}", f.force_unit),
                    ));
                }
            };
            let event_probabilities: [f64; 3] =
                f.event_probabilities.try_into().map_err(|v: Vec<f64>| {
                    FieldError::new(
                        field("event_probabilities"),
                        format!("{} values, expected 3", v.len()),
                    )
                })?;
            let material_probabilities = if f.material_probabilities.is_empty() {
                None
            } else {
                Some(
                    <[f64; 4]>::try_from(f.material_probabilities).map_err(|v: Vec<f64>| {
                        FieldError::new(
                            field("material_probabilities"),
                            format!("{} values, expected 0 or 4", v.len()),
                        )
                    })?,
                )
            };
            let slip_direction = match pb::SlipDirection::try_from(f.slip_direction) {
                Ok(pb::SlipDirection::Unspecified) => None,
                Ok(d) => SlipDirection::ALL
                    .into_iter()
                    .find(|&s| slip_direction_to_proto(s) == d as i32),
                Err(_) => {
                    return Err(FieldError::new(
                        field("slip_direction"),
                        format!("unknown value {}", f.slip_direction),
                    ));
                }
            };
            let slip_direction_probabilities = if f.slip_direction_probabilities.is_empty() {
                None
            } else {
                Some(
                    <[f64; 6]>::try_from(f.slip_direction_probabilities).map_err(
                        |v: Vec<f64>| {
                            FieldError::new(
                                field("slip_direction_probabilities"),
                                format!("{} values, expected 0 or 6", v.len()),
                            )
                        },
                    )?,
                )
            };
            Ok(FingerResult {
                finger: f.finger,
                tared: f.tared,
                event,
                event_probabilities,
                material,
                material_probabilities,
                slip_direction,
                slip_direction_probabilities,
                force: f.force,
                force_unit,
                contact_location: f.contact_location.map(|l| [l.row, l.col]),
                contact_area_pixels: f.contact_area_pixels as usize,
                contact_area_mm2: f.contact_area_mm2,
                desired_force: f.desired_force,
                mode,
                setpoint: f.setpoint,
            })
        })
        .collect::<Result<Vec<_>, FieldError>>()?;
    Ok(FrameResult {
        timestamp: m.timestamp,
        fingers,
    })
}

/// A slip direction as the proto enum's value.
fn slip_direction_to_proto(d: SlipDirection) -> i32 {
    (match d {
        SlipDirection::North => pb::SlipDirection::North,
        SlipDirection::East => pb::SlipDirection::East,
        SlipDirection::South => pb::SlipDirection::South,
        SlipDirection::West => pb::SlipDirection::West,
        SlipDirection::Clockwise => pb::SlipDirection::Clockwise,
        SlipDirection::Anticlockwise => pb::SlipDirection::Anticlockwise,
    }) as i32
}
