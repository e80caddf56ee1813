//! proto ↔ domain, one file per message family: [`values`] (vectors, points, poses, planes,
//! enums and the API names of sources), [`hands`] (descriptions and registrations), [`plan`]
//! (PlanGrasp requests and responses), [`reach`] (PlanReach), [`perception`] (the perception report), [`ros`]
//! (PointCloud2 in, MoveIt grasps out), [`tactile`] (sessions, frames and setpoints of the
//! Stabilize stream) and [`calibration`]. Decoding
//! treats a message as untrusted: every error names the offending field by its proto path.

pub mod calibration;
pub mod hands;
pub mod perception;
pub mod plan;
pub mod reach;
pub mod ros;
pub mod tactile;
pub mod values;

pub use calibration::*;
pub use hands::*;
pub use perception::*;
pub use plan::*;
pub use reach::*;
pub use ros::*;
pub use tactile::*;
pub use values::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::Limits;
    use graspd_core::HandCatalog;
    use graspd_core::PlannerOptions;
    use graspd_core::planning::PlannerMode;
    use graspd_proto::v1 as pb;
    use graspd_proto::v1::plan_grasp_request::{Hand, Input};

    #[test]
    fn hands_round_trip() {
        for h in HandCatalog::builtin().list() {
            assert_eq!(&hand_from_proto(hand_to_proto(h), "hand").unwrap(), h);
        }
    }

    #[test]
    fn options_round_trip_and_unset_means_default() {
        assert_eq!(options_from_proto(None).unwrap(), PlannerOptions::default());
        let o = PlannerOptions {
            seed: 7,
            mode: PlannerMode::WithoutOpposition,
            epsilon: 0.5,
            stage2_weights: [0.1, 0.9],
            lambda1: Some(0.03),
            check_collisions: false,
            ..PlannerOptions::default()
        };
        assert_eq!(options_from_proto(Some(options_to_proto(&o))).unwrap(), o);
    }

    #[test]
    fn bad_cloud_bytes_name_the_field() {
        let r = pb::PlanGraspRequest {
            input: Some(Input::Cloud(pb::PointCloud {
                points: vec![0; 13],
                ..Default::default()
            })),
            hand: Some(Hand::HandName("shadow".into())),
            ..Default::default()
        };
        let e = plan_request_from_proto(r, &Limits::default()).unwrap_err();
        assert_eq!(e.field(), Some("cloud.points"));
        assert!(
            e.to_string()
                .contains("byte length 13 is not a multiple of 12")
        );
    }

    #[test]
    fn bad_enum_values_name_the_field() {
        let r = pb::PlanGraspRequest {
            input: Some(Input::Cloud(pb::PointCloud::default())),
            hand: Some(Hand::HandName("shadow".into())),
            hints: Some(pb::PlanHints {
                grasp_type: 42,
                ..Default::default()
            }),
            ..Default::default()
        };
        let e = plan_request_from_proto(r, &Limits::default()).unwrap_err();
        assert_eq!(e.field(), Some("hints.grasp_type"));
    }
}
