//! ROS layouts in JSON, as rosbridge and `ros2 topic echo` write them: a `sensor_msgs/PointCloud2`
//! in (`cloud2`, its `data` base64 or an array of bytes) and `moveit_msgs/Grasp` out
//! (`moveit_grasps`, ROS 2 field names and nesting). The rules live in core
//! (`cloud::io::pointcloud2`, `planning::moveit_layout`).

use super::values::{PoseJson, Vec3Json};
use crate::error::ServiceError;
use crate::limits::Limits;
use base64::Engine;
use graspd_core::cloud::PointCloud;
use graspd_core::cloud::io::{PointCloud2Layout, PointField, read_pointcloud2};
use graspd_core::planning::Pose;
use graspd_core::planning::moveit_grasp::{
    GripperTranslation, JointTrajectory, MoveItGrasp, ros_duration,
};
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::fmt;
use utoipa::ToSchema;

/// `sensor_msgs/PointField`.
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PointFieldJson {
    pub name: String,
    pub offset: u32,
    /// 1 INT8, 2 UINT8, 3 INT16, 4 UINT16, 5 INT32, 6 UINT32, 7 FLOAT32, 8 FLOAT64.
    pub datatype: u32,
    #[serde(default)]
    pub count: u32,
}

/// `std_msgs/Header` (the frame; a stamp, when sent, is ignored).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct HeaderJson {
    #[serde(default)]
    pub frame_id: String,
}

/// `sensor_msgs/PointCloud2` (docs/api.md, "ROS payloads").
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PointCloud2Json {
    /// Its `frame_id` is the frame the plan is returned in.
    #[serde(default)]
    pub header: HeaderJson,
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointFieldJson>,
    #[serde(default)]
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    /// Base64 (rosbridge's encoding of uint8[]) or an array of byte values.
    #[schema(value_type = String)]
    pub data: Bytes,
    #[serde(default)]
    pub is_dense: bool,
}

/// Bytes as a base64 string or an array of numbers 0–255.
#[derive(Debug, Clone, PartialEq)]
pub struct Bytes(pub Vec<u8>);

impl<'de> Deserialize<'de> for Bytes {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Bytes;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a base64 string or an array of bytes")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Bytes, E> {
                base64::engine::general_purpose::STANDARD
                    .decode(s)
                    .map(Bytes)
                    .map_err(|e| E::custom(format!("invalid base64: {e}")))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Bytes, A::Error> {
                let mut v = Vec::with_capacity(s.size_hint().unwrap_or(0).min(1 << 20));
                while let Some(b) = s.next_element::<u8>()? {
                    v.push(b);
                }
                Ok(Bytes(v))
            }
        }
        d.deserialize_any(V)
    }
}

impl PointCloud2Json {
    fn layout(&self) -> PointCloud2Layout {
        PointCloud2Layout {
            height: self.height,
            width: self.width,
            fields: self
                .fields
                .iter()
                .map(|f| PointField {
                    name: f.name.clone(),
                    offset: f.offset,
                    datatype: f.datatype,
                    count: f.count,
                })
                .collect(),
            is_bigendian: self.is_bigendian,
            point_step: self.point_step,
            row_step: self.row_step,
            is_dense: self.is_dense,
        }
    }
}

/// Decodes the request's `cloud2`, refusing more points than the limit before reading them.
pub fn cloud2_from_json(c: &PointCloud2Json, limits: &Limits) -> Result<PointCloud, ServiceError> {
    let layout = c.layout();
    limits.check_points(layout.points().unwrap_or(u64::MAX), "cloud2.width")?;
    Ok(read_pointcloud2(&layout, &c.data.0, "cloud2")?)
}

/// `builtin_interfaces/Duration`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct DurationJson {
    pub sec: i32,
    pub nanosec: u32,
}

impl DurationJson {
    fn of(seconds: f64) -> Self {
        let (sec, nanosec) = ros_duration(seconds);
        Self { sec, nanosec }
    }
}

/// `trajectory_msgs/JointTrajectoryPoint` (positions and time).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct JointTrajectoryPointJson {
    pub positions: Vec<f64>,
    pub time_from_start: DurationJson,
}

/// `trajectory_msgs/JointTrajectory`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct JointTrajectoryJson {
    pub header: HeaderJson,
    pub joint_names: Vec<String>,
    pub points: Vec<JointTrajectoryPointJson>,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PoseStampedJson {
    pub header: HeaderJson,
    pub pose: PoseJson,
}

/// `geometry_msgs/Vector3Stamped`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Vector3StampedJson {
    pub header: HeaderJson,
    #[schema(value_type = super::super::schemas::Vec3InputDoc)]
    pub vector: Vec3Json,
}

/// `moveit_msgs/GripperTranslation`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct GripperTranslationJson {
    pub direction: Vector3StampedJson,
    pub desired_distance: f64,
    pub min_distance: f64,
}

/// `moveit_msgs/Grasp` (ROS 2 field names and nesting; how each is filled:
/// `graspd_core::planning::moveit_layout`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct MoveItGraspJson {
    pub id: String,
    pub pre_grasp_posture: JointTrajectoryJson,
    pub grasp_posture: JointTrajectoryJson,
    pub grasp_pose: PoseStampedJson,
    pub grasp_quality: f64,
    pub pre_grasp_approach: GripperTranslationJson,
    pub post_grasp_retreat: GripperTranslationJson,
    pub post_place_retreat: GripperTranslationJson,
    pub max_contact_force: f64,
    pub allowed_touch_objects: Vec<String>,
}

fn header(frame_id: &str) -> HeaderJson {
    HeaderJson {
        frame_id: frame_id.to_string(),
    }
}

fn trajectory(t: &JointTrajectory, frame_id: &str) -> JointTrajectoryJson {
    JointTrajectoryJson {
        header: header(frame_id),
        joint_names: t.joint_names.clone(),
        points: t
            .points
            .iter()
            .map(|p| JointTrajectoryPointJson {
                positions: p.positions.clone(),
                time_from_start: DurationJson::of(p.time_from_start),
            })
            .collect(),
    }
}

fn translation(t: &GripperTranslation) -> GripperTranslationJson {
    GripperTranslationJson {
        direction: Vector3StampedJson {
            header: header(&t.frame_id),
            vector: (&t.direction).into(),
        },
        desired_distance: t.desired_distance,
        min_distance: t.min_distance,
    }
}

impl From<&MoveItGrasp> for MoveItGraspJson {
    fn from(g: &MoveItGrasp) -> Self {
        Self {
            id: g.id.clone(),
            pre_grasp_posture: trajectory(&g.pre_grasp_posture, &g.frame_id),
            grasp_posture: trajectory(&g.grasp_posture, &g.frame_id),
            grasp_pose: PoseStampedJson {
                header: header(&g.frame_id),
                pose: (&Pose::from_isometry(&g.grasp_pose)).into(),
            },
            grasp_quality: g.grasp_quality,
            pre_grasp_approach: translation(&g.pre_grasp_approach),
            post_grasp_retreat: translation(&g.post_grasp_retreat),
            post_place_retreat: translation(&g.post_place_retreat),
            max_contact_force: g.max_contact_force,
            allowed_touch_objects: g.allowed_touch_objects.clone(),
        }
    }
}
