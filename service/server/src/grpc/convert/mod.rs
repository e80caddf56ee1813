//! The conversions between `graspd.v1` proto messages and the server's request and answer
//! types, both ways (the server decodes requests and encodes plans; `graspctl` does the
//! reverse). Decoding treats the
//! message as untrusted: every error names the offending field by its proto path.
//!
//! One file per message family: [`hands`], [`plan`] (PlanGrasp requests and responses), [`ros`]
//! (PointCloud2 in, MoveIt grasps out); values, the perception report, tactile sessions and
//! calibrations are `graspd-api`'s (`graspd_api::convert`), re-exported here.

mod hands;
mod plan;
mod ros;

pub use graspd_api::convert::*;
pub use hands::*;
pub use plan::*;
pub use ros::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facade::Limits;
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
