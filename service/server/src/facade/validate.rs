//! The request rules the facade owns (the options' ranges are `PlannerOptions::validate`'s).

use super::ServiceError;
use graspd_core::cloud::Plane;
use graspd_core::{FieldError, HandDescription, PlanHints};
use nalgebra::Point3;

pub(super) fn rename_hand_field(e: FieldError, to: &str) -> ServiceError {
    let field = match e.field.strip_prefix("hand") {
        Some(rest) => format!("{to}{rest}"),
        None => e.field,
    };
    ServiceError::InvalidArgument(FieldError::new(field, e.message))
}

pub(super) fn finite_point(p: &Point3<f64>, field: &str) -> Result<(), FieldError> {
    if p.coords.iter().all(|v| v.is_finite() && v.abs() <= 1.0e3) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            "coordinates must be finite and within ±1000 m",
        ))
    }
}

pub(super) fn validate_hints(
    mut hints: PlanHints,
    hand: &HandDescription,
) -> Result<PlanHints, FieldError> {
    if let Some(t) = hints.grasp_type
        && !hand.supports(t)
    {
        let can: Vec<&str> = hand.realisable_types().iter().map(|t| t.name()).collect();
        return Err(FieldError::new(
            "hints.grasp_type",
            format!(
                "hand '{}' cannot realise {t} (it realises: {})",
                hand.name,
                can.join(", ")
            ),
        ));
    }
    if let Some(p) = &hints.attention_point {
        finite_point(p, "hints.attention_point")?;
    }
    // Set by perception, or by a library caller with its own model: probabilities.
    if let Some(p) = &hints.detected_types
        && !p.iter().all(|v| (0.0..=1.0).contains(v))
    {
        return Err(FieldError::new(
            "hints.detected_types",
            format!("must be six probabilities in [0, 1], got {p:?}"),
        ));
    }
    if let Some(p) = &hints.viewpoint {
        finite_point(p, "hints.viewpoint")?;
    }
    if let Some(plane) = hints.support_plane {
        hints.support_plane = Some(Plane::checked(
            plane.normal,
            plane.offset,
            "hints.support_plane",
        )?);
    }
    if let Some(up) = hints.up {
        let len = up.norm();
        if !len.is_finite() || len < 1e-9 {
            return Err(FieldError::new("hints.up", "must be finite and non-zero"));
        }
        hints.up = Some(up / len);
    }
    Ok(hints)
}
