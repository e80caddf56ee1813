//! PlanReach (issue 18 part 4): a reaching trajectory to a grasp, planned by
//! `graspd_core::reaching` (its rules and bounds are the domain's), panics contained. With the
//! scene's RGB-D frame, the objects segmented on its support plane but the grasp's become
//! upright boxes among the obstacles (`reaching::scene_boxes`).

use super::{GraspService, ServiceError, guarded};
use graspd_api::request::ReachCall;
use graspd_core::FieldError;
use graspd_core::perception::{CloudFrame, SegmentationParams, depth_to_cloud, objects_on_plane};
use graspd_core::reaching::scene_boxes::obstacle_boxes;
use graspd_core::reaching::{MAX_OBSTACLES, Trajectory, plan_reach};
use nalgebra::Point3;
use std::time::Instant;

impl GraspService {
    /// The trajectory and the time it took, ms. A reach that cannot keep its clearance is bad
    /// input naming the obstacle in the way.
    pub fn plan_reach(&self, call: ReachCall) -> Result<(Trajectory, f64), ServiceError> {
        let started = Instant::now();
        let mut request = call.reach;
        if let Some(frame) = &call.scene {
            let decoded = self.decode_frame(frame, "scene")?;
            // In the frame's world frame when it has one, else its camera's: the poses' frame.
            let cloud = depth_to_cloud(&decoded, CloudFrame::World);
            let points = &cloud.cloud.points;
            let (plane, clusters, _) =
                objects_on_plane(points, request.scene.table, &SegmentationParams::default());
            let objects: Vec<Vec<Point3<f64>>> = clusters
                .iter()
                .map(|c| c.iter().map(|&i| points[i]).collect())
                .collect();
            let viewpoint = frame
                .camera_to_world
                .map_or(Point3::origin(), |t| Point3::from(t.translation.vector));
            let goal = Point3::from(request.goal.translation.vector);
            let boxes = obstacle_boxes(&objects, plane.as_ref(), &viewpoint, &goal);
            if request.scene.obstacles.len() + boxes.len() > MAX_OBSTACLES {
                return Err(FieldError::new(
                    "scene",
                    format!(
                        "{} objects in the frame and {} obstacles given, more than {MAX_OBSTACLES}",
                        boxes.len(),
                        request.scene.obstacles.len()
                    ),
                )
                .into());
            }
            request.scene.obstacles.extend(boxes);
            request.scene.table = request.scene.table.or(plane);
        }
        let trajectory = guarded("the reach planner", || {
            plan_reach(&request).map_err(ServiceError::InvalidArgument)
        })?;
        Ok((trajectory, started.elapsed().as_secs_f64() * 1e3))
    }
}
