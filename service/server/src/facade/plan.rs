//! Planning: a request validated, perceived (RGB-D) and planned (Algorithm 4).

use super::validate::validate_hints;
use super::{
    GraspService, ImageHints, OutputOptions, PlanRequest, PlanSource, ServiceError, guarded,
};
use graspd_core::perception::segmentation::SegmentationParams;
use graspd_core::perception::{
    DecodedFrame, FusionReport, GraspInformation, InformationParams, PerceptionModels, RgbdFrame,
    RgbdLimits, fuse_views, grasp_information,
};
use graspd_core::plan_overlay::draw_overlay;
use graspd_core::plan_scene::{plan_scene, to_glb};
use graspd_core::planning::PlaneSource;
use graspd_core::planning::moveit_layout::moveit_grasps;
use graspd_core::{FieldError, GraspPlan, HandDescription, PlanHints, PlanInput};

/// A decoded frame and the information extracted from it, kept until the plan is made.
struct Perceived {
    decoded: DecodedFrame,
    info: GraspInformation,
    /// The support plane came from the frame (the caller gave none).
    plane_from_frame: bool,
    /// What the further views added (`extra_views`).
    fusion: Option<FusionReport>,
}

impl Perceived {
    /// Puts the perception report (and the overlay, if asked for) into the plan.
    fn attach(self, plan: &mut GraspPlan, output: &OutputOptions) {
        if let Some(e) = &self.info.model_error {
            plan.warnings.push(format!(
                "the grasp-type model failed ({e}); the geometric rule decided the type"
            ));
        }
        if self.plane_from_frame && plan.plane_source == PlaneSource::Request {
            plan.plane_source = PlaneSource::Detected;
        }
        let mut report = self.info.report(
            self.decoded.width,
            self.decoded.height,
            output.probability_maps_max_side as usize,
        );
        if let Some(f) = &self.fusion {
            report.fused_views = f.views;
            report.fused_points = f.added_points;
            report.object_points += f.added_points;
        }
        if output.overlay {
            report.overlay_png = Some(draw_overlay(&self.decoded, &self.info, plan));
        }
        plan.perception = Some(report);
    }
}

impl GraspService {
    /// Validates a request and plans (Algorithm 4). Blocking and CPU-bound: async callers run it
    /// on a blocking thread. A planner panic becomes `Internal`, so one bad request cannot take
    /// the service down.
    pub fn plan(&self, request: PlanRequest) -> Result<GraspPlan, ServiceError> {
        let output = request.output.clone();
        let (input, perceived) = self.prepare_with_perception(request)?;
        // What the scene draws besides the plan: the points planned on and the hand's model.
        let scene = output
            .scene_glb
            .then(|| (input.cloud.points.clone(), input.kinematics.clone()));
        guarded("the planner", || {
            let mut plan = graspd_core::plan(input).map_err(ServiceError::from)?;
            if let Some((points, kinematics)) = &scene {
                plan.scene_glb = Some(to_glb(&plan_scene(points, &plan, kinematics.as_deref())));
            }
            if let Some(p) = perceived {
                p.attach(&mut plan, &output);
            }
            if output.moveit_grasps {
                plan.moveit_grasps = moveit_grasps(&plan, &output.frame_id);
            }
            Ok(plan)
        })
    }

    /// Checks a request against the catalog and the limits and turns it into planner input.
    pub fn prepare(&self, request: PlanRequest) -> Result<PlanInput, ServiceError> {
        self.prepare_with_perception(request)
            .map(|(input, _)| input)
    }

    /// [`Self::prepare`], and for an RGB-D frame what perception found in it (Ω, method.md §4):
    /// the planner then plans on the target object's points, with the frame's support plane,
    /// the camera as viewpoint, and the model's type probabilities and attention point unless
    /// the caller gave their own.
    fn prepare_with_perception(
        &self,
        request: PlanRequest,
    ) -> Result<(PlanInput, Option<Perceived>), ServiceError> {
        let (hand, kinematics) = self.choose_hand(request.hand)?;
        let mut hints = validate_hints(request.hints, &hand)?;
        request.options.validate()?;
        self.inner.limits.check_options(&request.options)?;
        let max_views = self.inner.limits.max_views;
        if request.extra_views.len() > max_views {
            return Err(ServiceError::TooLarge(FieldError::new(
                "extra_views",
                format!(
                    "{} further views exceed the configured limit of {max_views} (max_views)",
                    request.extra_views.len()
                ),
            )));
        }
        let (mut cloud, perceived) = match request.source {
            PlanSource::Cloud(cloud) => {
                if !request.extra_views.is_empty() {
                    return Err(FieldError::new(
                        "extra_views",
                        "are further RGB-D views: they need rgbd input (fuse clouds yourself)",
                    )
                    .into());
                }
                if let Some(field) = request.image_hints.field() {
                    return Err(FieldError::new(
                        field,
                        "is an image hint: it needs rgbd input (for a cloud give hints.attention_point)",
                    )
                    .into());
                }
                (cloud, None)
            }
            PlanSource::Rgbd(frame) => {
                let mut perceived = self.perceive(&frame, &request.image_hints, &hand, &hints)?;
                let info = &perceived.info;
                hints.support_plane = hints.support_plane.or(info.plane);
                hints.viewpoint = hints.viewpoint.or(Some(info.viewpoint));
                // A pixel the caller named gives a binding attention point; the model's is a
                // suggestion (PlanHints::detected_attention).
                if request.image_hints.attention_pixel.is_some() {
                    hints.attention_point = hints.attention_point.or(info.attention_point);
                } else {
                    hints.detected_attention = info.attention_point;
                }
                if hints.grasp_type.is_none() {
                    hints.detected_types = info.detection.as_ref().map(|d| d.probabilities);
                }
                let mut object = info.object.clone();
                if !request.extra_views.is_empty() {
                    if frame.camera_to_world.is_none() {
                        return Err(FieldError::new(
                            "rgbd.camera_to_world",
                            "is required with extra_views: the views are fused in the world frame",
                        )
                        .into());
                    }
                    let views = request
                        .extra_views
                        .iter()
                        .enumerate()
                        .map(|(i, f)| self.decode_frame(f, &format!("extra_views[{i}]")))
                        .collect::<Result<Vec<_>, _>>()?;
                    let (fused, report) = fuse_views(
                        &object,
                        hints.support_plane.as_ref(),
                        &views,
                        &SegmentationParams::default(),
                        "extra_views",
                    )?;
                    // The far side is measured: no completion, and each point's normal
                    // faces the camera that saw it; the first camera still sets the approach
                    // side, as for one view.
                    hints.seen_from = std::iter::once((object.len(), info.viewpoint))
                        .chain(report.seen_from.iter().copied())
                        .collect();
                    object = fused;
                    perceived.fusion = Some(report);
                }
                (object, Some(perceived))
            }
        };
        let max_points = self.inner.limits.max_points;
        if cloud.len() > max_points {
            return Err(ServiceError::TooLarge(FieldError::new(
                if perceived.is_some() {
                    "rgbd"
                } else {
                    "cloud.points"
                },
                format!(
                    "{} points exceed the configured limit of {max_points} (max_points)",
                    cloud.len()
                ),
            )));
        }
        cloud.validate("cloud", max_points)?;
        Ok((
            PlanInput {
                cloud,
                hand,
                hints,
                options: request.options,
                kinematics,
                grasp_quality: self.inner.grasp_quality.clone(),
            },
            perceived,
        ))
    }

    /// Decodes a frame and extracts Ω from it.
    fn perceive(
        &self,
        frame: &RgbdFrame,
        image_hints: &ImageHints,
        hand: &HandDescription,
        hints: &PlanHints,
    ) -> Result<Perceived, ServiceError> {
        let t = std::time::Instant::now();
        let decoded = self.decode_frame(frame, "rgbd")?;
        let decode_seconds = t.elapsed().as_secs_f64();
        let target = image_hints.target()?;
        let models = PerceptionModels {
            grasp_type: self.inner.grasp_type_model.as_deref(),
            recogniser: self.inner.recogniser.as_deref(),
        };
        let mut info = grasp_information(
            &decoded,
            target,
            hints.support_plane,
            models,
            &hand.realisable_types(),
            &InformationParams::default(),
        )?;
        info.timings.decode = decode_seconds;
        info.timings.total += decode_seconds;
        Ok(Perceived {
            decoded,
            info,
            plane_from_frame: hints.support_plane.is_none(),
            fusion: None,
        })
    }

    /// Decodes a frame (`field` names it) within the configured pixel limit.
    pub(super) fn decode_frame(
        &self,
        frame: &RgbdFrame,
        field: &str,
    ) -> Result<DecodedFrame, ServiceError> {
        let limits = RgbdLimits {
            max_pixels: self.inner.limits.max_image_pixels,
        };
        let pixels = frame.width.saturating_mul(frame.height);
        if pixels > limits.max_pixels {
            return Err(ServiceError::TooLarge(FieldError::new(
                field,
                format!(
                    "{}×{} = {pixels} pixels exceed the configured limit of {} (max_image_pixels)",
                    frame.width, frame.height, limits.max_pixels
                ),
            )));
        }
        Ok(frame.decode(field, &limits)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facade::{HandChoice, Limits};
    use graspd_core::GraspType;
    use graspd_core::PlannerOptions;
    use graspd_core::cloud::{Plane, PointCloud};
    use nalgebra::Point3;
    use nalgebra::Vector3;

    fn cylinder(n: usize) -> PointCloud {
        let pts = (0..n)
            .map(|i| {
                let a = i as f64 * 0.7;
                Point3::new(
                    0.035 * a.cos(),
                    0.035 * a.sin(),
                    0.1 * (i as f64 / n as f64),
                )
            })
            .collect();
        PointCloud::new(pts)
    }

    fn request(hand: &str) -> PlanRequest {
        PlanRequest {
            source: PlanSource::Cloud(cylinder(100)),
            extra_views: Vec::new(),
            hand: HandChoice::Name(hand.into()),
            options: PlannerOptions::default(),
            hints: PlanHints::default(),
            image_hints: ImageHints::default(),
            output: OutputOptions::default(),
        }
    }

    fn field_of(r: Result<PlanInput, ServiceError>) -> String {
        r.unwrap_err().field().unwrap_or("-").to_string()
    }

    #[test]
    fn valid_request_prepares() {
        let s = GraspService::builtin(Limits::default());
        let input = s.prepare(request("shadow")).unwrap();
        assert_eq!(input.hand.name, "shadow");
        assert_eq!(input.cloud.len(), 100);
    }

    #[test]
    fn errors_name_the_field() {
        let s = GraspService::builtin(Limits::default());
        let e = s.prepare(request("foo")).unwrap_err();
        assert_eq!(e.field(), Some("hand_name"));
        assert!(
            e.to_string()
                .contains("known: barrett, parallel_gripper, shadow")
        );

        let mut r = request("parallel_gripper");
        r.hints.grasp_type = Some(GraspType::Tripod);
        assert_eq!(field_of(s.prepare(r)), "hints.grasp_type");

        let mut r = request("shadow");
        r.options.epsilon = f64::NAN;
        assert_eq!(field_of(s.prepare(r)), "options.epsilon");

        let mut r = request("shadow");
        r.options.max_iterations = 10_000_000;
        assert_eq!(field_of(s.prepare(r)), "options.max_iterations");

        // The planner's ranges are the edge's: μ = 7 is refused here, before any planning.
        let mut r = request("shadow");
        r.options.friction = 7.0;
        assert_eq!(field_of(s.prepare(r)), "options.friction");
        let mut r = request("shadow");
        r.options.opposition_candidates = 4;
        assert_eq!(field_of(s.prepare(r)), "options.opposition_candidates");

        let mut r = request("shadow");
        r.hints.support_plane = Some(Plane {
            normal: Vector3::zeros(),
            offset: 0.0,
        });
        assert_eq!(field_of(s.prepare(r)), "hints.support_plane");

        let mut hand = s.get_hand("barrett", "name").unwrap();
        hand.geometry.max_aperture = -1.0;
        let mut r = request("shadow");
        r.hand = HandChoice::Inline(Box::new(hand));
        assert_eq!(
            field_of(s.prepare(r)),
            "hand_description.geometry.max_aperture"
        );
    }

    /// `max_iterations` is the server's limit: a request within the planner's range but above
    /// the configured limit is refused naming it, and a server configured higher accepts it.
    #[test]
    fn the_iteration_limit_is_configurable() {
        let mut r = request("shadow");
        r.options.max_iterations = 200_000;
        let e = GraspService::builtin(Limits::default())
            .prepare(r.clone())
            .unwrap_err();
        assert_eq!(e.field(), Some("options.max_iterations"));
        assert!(e.to_string().contains("100000"), "{e}");
        let s = GraspService::builtin(Limits {
            max_iterations: 500_000,
            ..Limits::default()
        });
        assert!(s.prepare(r).is_ok());
    }

    #[test]
    fn limits_and_image_hints_on_clouds() {
        let s = GraspService::builtin(Limits {
            max_points: 50,
            ..Limits::default()
        });
        assert!(matches!(
            s.prepare(request("shadow")),
            Err(ServiceError::TooLarge(_))
        ));
        let s = GraspService::builtin(Limits::default());
        let mut r = request("shadow");
        r.image_hints.most_salient = true;
        assert_eq!(field_of(s.prepare(r)), "hints.most_salient");
        let mut r = request("shadow");
        r.image_hints.attention_pixel = Some((3, 4));
        assert_eq!(field_of(s.prepare(r)), "hints.attention_pixel");
    }
}
