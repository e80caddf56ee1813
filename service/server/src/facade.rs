//! The one facade that both transports call: the hand catalog, the configured limits, and the
//! validation of a plan request before it reaches the planner. Plain Rust and synchronous (no
//! tonic, axum, tokio or proto types), so it also serves as the library entry point.

use crate::hand_store::{self, HandUpload};
use graspd_core::cloud::{Plane, PointCloud};
use graspd_core::perception::segmentation::SegmentationParams;
use graspd_core::perception::{
    DecodedFrame, FusionReport, GraspInformation, GraspTypeModel, InformationParams, RgbdFrame,
    RgbdLimits, TargetHint, draw_overlay, fuse_views, grasp_information,
};
use graspd_core::planning::{KinematicModel, PlaneSource};
use graspd_core::tactile::{
    DetectorChoice, EventDetector, FingerConfig, Frame, FrameResult, LayoutSpec, LstmDetector,
    ModelFreeThresholds, SensorCatalog, SensorLayout, Stabilizer, StabilizerConfig, TactileModel,
    TareConfig,
};
use graspd_core::{
    FieldError, GraspPlan, HandCatalog, HandDescription, PlanError, PlanHints, PlanInput,
    PlannerOptions,
};
use nalgebra::Point3;
use std::collections::{BTreeMap, BTreeSet};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, RwLock};
use thiserror::Error;

/// Limits on untrusted input, enforced by the transports (bytes) and by the facade (points).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest gRPC message or REST body, bytes.
    pub max_message_bytes: usize,
    /// Largest cloud, points.
    pub max_points: usize,
    /// Plans computed at once; more wait (planning is CPU-bound).
    pub max_concurrent_plans: usize,
    /// Plan requests waiting for a planner; more are shed (RESOURCE_EXHAUSTED, 503).
    pub max_queued_plans: usize,
    /// Tactile sessions open at once (streams and analyze calls); more are refused
    /// (RESOURCE_EXHAUSTED, 503).
    pub max_tactile_sessions: usize,
    /// Largest RGB-D frame, `width × height` pixels (also what a PNG or JPEG may decode to).
    pub max_image_pixels: usize,
    /// Most further views (`extra_views`) fused into one plan request.
    pub max_views: usize,
    /// Most stage-1 iterations a request may ask for (`options.max_iterations`): what one plan
    /// may cost in CPU. Within the planner's own bound, [`graspd_core::planning::MAX_ITERATIONS`].
    pub max_iterations: usize,
}

/// Default of [`Limits::max_iterations`].
pub const DEFAULT_MAX_ITERATIONS: usize = 100_000;

impl Limits {
    /// The limits' share of the options' rules (their ranges are
    /// `PlannerOptions::validate`'s): how much CPU one request may ask for.
    pub fn check_options(&self, o: &PlannerOptions) -> Result<(), FieldError> {
        if o.max_iterations > self.max_iterations {
            return Err(FieldError::new(
                "options.max_iterations",
                format!(
                    "must be at most {}, this server's limit (max_iterations), got {}",
                    self.max_iterations, o.max_iterations
                ),
            ));
        }
        Ok(())
    }
}

/// Default of [`Limits::max_views`].
pub const DEFAULT_MAX_VIEWS: usize = 8;

/// Default of [`Limits::max_tactile_sessions`].
pub const DEFAULT_MAX_TACTILE_SESSIONS: usize = 64;

/// Default of [`Limits::max_queued_plans`], per planner of `max_concurrent_plans`.
pub const QUEUED_PLANS_PER_PLANNER: usize = 4;

fn default_concurrent_plans() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 32 * 1024 * 1024,
            max_points: 500_000,
            max_concurrent_plans: default_concurrent_plans(),
            max_queued_plans: QUEUED_PLANS_PER_PLANNER * default_concurrent_plans(),
            max_tactile_sessions: DEFAULT_MAX_TACTILE_SESSIONS,
            max_image_pixels: RgbdLimits::default().max_pixels,
            max_views: DEFAULT_MAX_VIEWS,
            max_iterations: DEFAULT_MAX_ITERATIONS,
        }
    }
}

/// What the plan is computed from.
#[derive(Debug, Clone, PartialEq)]
pub enum PlanSource {
    /// A cloud as decoded at the edge; the facade validates it.
    Cloud(PointCloud),
    /// An RGB-D frame as received; the facade decodes and validates it (method.md §4).
    Rgbd(Box<RgbdFrame>),
}

/// Which hand to plan for.
#[derive(Debug, Clone, PartialEq)]
pub enum HandChoice {
    /// A hand of the catalog.
    Name(String),
    /// An inline description, validated like the data files.
    Inline(Box<HandDescription>),
}

/// Hints that only make sense on an image (RGB-D input); with a cloud they are refused rather
/// than ignored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImageHints {
    /// The object at this pixel (u, v), and the attention point there.
    pub attention_pixel: Option<(u32, u32)>,
    /// The object with most pixels in [u_min, u_max) × [v_min, v_max).
    pub region: Option<[u32; 4]>,
    /// The most salient object (the default without a pixel or region).
    pub most_salient: bool,
}

impl ImageHints {
    /// The first hint given, by its field name.
    pub fn field(&self) -> Option<&'static str> {
        if self.attention_pixel.is_some() {
            Some("hints.attention_pixel")
        } else if self.region.is_some() {
            Some("hints.region")
        } else if self.most_salient {
            Some("hints.most_salient")
        } else {
            None
        }
    }

    /// The segmentation's target hint; errors name the conflicting hint.
    fn target(&self) -> Result<TargetHint, FieldError> {
        match (self.attention_pixel, self.region) {
            (Some(_), Some(_)) => Err(FieldError::new(
                "hints.region",
                "give either attention_pixel or region, not both",
            )),
            (Some((u, v)), None) => Ok(TargetHint::Pixel { u, v }),
            (None, Some([u_min, v_min, u_max, v_max])) => {
                if u_min >= u_max || v_min >= v_max {
                    return Err(FieldError::new(
                        "hints.region",
                        format!(
                            "is empty: u {u_min}..{u_max}, v {v_min}..{v_max} (need u_min < u_max and v_min < v_max)"
                        ),
                    ));
                }
                Ok(TargetHint::Region {
                    u_min,
                    v_min,
                    u_max,
                    v_max,
                })
            }
            (None, None) => Ok(TargetHint::Auto),
        }
    }
}

/// What to return besides the plan (RGB-D input).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OutputOptions {
    /// Return the grasp-type model's six maps with the longer side at most this many pixels
    /// (0 = do not).
    pub probability_maps_max_side: u32,
    /// Draw the overlay PNG (ROI, attention point, heat map of s*, contacts, opposition).
    pub overlay: bool,
}

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

/// One plan request in domain terms, as both transports produce it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    pub source: PlanSource,
    /// Further views of the scene (RGB-D input only; `extra_views`).
    pub extra_views: Vec<RgbdFrame>,
    pub hand: HandChoice,
    pub options: PlannerOptions,
    pub hints: PlanHints,
    pub image_hints: ImageHints,
    pub output: OutputOptions,
}

/// Errors of the facade; each transport maps them to its status codes.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ServiceError {
    /// Bad input (gRPC INVALID_ARGUMENT, HTTP 400).
    #[error(transparent)]
    InvalidArgument(FieldError),
    /// A named thing does not exist (NOT_FOUND, 404).
    #[error(transparent)]
    NotFound(FieldError),
    /// Input over a configured limit (RESOURCE_EXHAUSTED, 413).
    #[error(transparent)]
    TooLarge(FieldError),
    /// A configured capacity is used up, retry later (RESOURCE_EXHAUSTED, 503).
    #[error("{0}")]
    Exhausted(String),
    /// The planner's queue is full: the request was shed, retry in a second
    /// (RESOURCE_EXHAUSTED with `retry-after-ms`, 503 with `Retry-After`).
    #[error("{0}")]
    Overloaded(String),
    /// A name is taken (ALREADY_EXISTS, 409).
    #[error(transparent)]
    AlreadyExists(FieldError),
    /// Valid but not implemented yet (UNIMPLEMENTED, 501).
    #[error("{0}")]
    Unimplemented(String),
    /// A bug: the planner failed (INTERNAL, 500).
    #[error("internal error: {0}")]
    Internal(String),
}

impl ServiceError {
    /// The offending field, when the error is about one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ServiceError::InvalidArgument(e)
            | ServiceError::NotFound(e)
            | ServiceError::AlreadyExists(e)
            | ServiceError::TooLarge(e) => Some(&e.field),
            _ => None,
        }
    }
}

impl From<FieldError> for ServiceError {
    fn from(e: FieldError) -> Self {
        ServiceError::InvalidArgument(e)
    }
}

impl From<PlanError> for ServiceError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::InvalidInput(f) => ServiceError::InvalidArgument(f),
            PlanError::Unimplemented(m) => ServiceError::Unimplemented(m),
        }
    }
}

/// The grasp-planning service. Cheap to clone (shared state).
#[derive(Debug, Clone)]
pub struct GraspService {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    hands: RwLock<Hands>,
    sensors: SensorCatalog,
    limits: Limits,
    /// Tactile sessions open now.
    tactile_sessions: Arc<AtomicUsize>,
    /// The grasp-type network (method.md §4), when configured and loaded.
    grasp_type_model: Option<Arc<GraspTypeModel>>,
    /// The tactile LSTM detector (method.md §5), when loaded.
    tactile_model: Option<Arc<TactileModel>>,
}

/// The hands: descriptions by name, the kinematics of those that have them, and where
/// registrations go.
#[derive(Debug, Default)]
struct Hands {
    catalog: HandCatalog,
    models: BTreeMap<String, Arc<KinematicModel>>,
    /// Names of hands registered at run time (in `dir`): the ones `replace` may replace.
    registered: BTreeSet<String>,
    dir: Option<PathBuf>,
}

/// The answer to a registration.
#[derive(Debug, Clone, PartialEq)]
pub struct RegisteredHand {
    pub description: HandDescription,
    /// Joint names of the model, in the order plans list them.
    pub joints: Vec<String>,
    /// Stored in the hands directory (else in memory only).
    pub persisted: bool,
}

/// Hands to load at start (configuration).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HandSetup {
    /// Registered hands persist here and are loaded again at start.
    pub hands_dir: Option<PathBuf>,
    /// `(name, model file)` pairs read at start (MJCF `.xml` or URDF `.urdf`).
    pub imports: Vec<(String, PathBuf)>,
}

impl GraspService {
    pub fn new(catalog: HandCatalog, limits: Limits) -> Self {
        Self {
            inner: Arc::new(Inner {
                hands: RwLock::new(Hands {
                    catalog,
                    ..Hands::default()
                }),
                sensors: SensorCatalog::builtin(),
                limits,
                tactile_sessions: Arc::new(AtomicUsize::new(0)),
                grasp_type_model: None,
                tactile_model: None,
            }),
        }
    }

    /// Sets the grasp-type network used for RGB-D input (at start, before the service is
    /// cloned).
    pub fn with_grasp_type_model(mut self, model: Arc<GraspTypeModel>) -> Self {
        Arc::get_mut(&mut self.inner)
            .expect("the model is set at start, before the service is shared")
            .grasp_type_model = Some(model);
        self
    }

    /// Sets the tactile detector model (at start, before the service is cloned).
    pub fn with_tactile_model(mut self, model: Arc<TactileModel>) -> Self {
        Arc::get_mut(&mut self.inner)
            .expect("the model is set at start, before the service is shared")
            .tactile_model = Some(model);
        self
    }

    /// The loaded tactile model, if any.
    pub fn tactile_model(&self) -> Option<&Arc<TactileModel>> {
        self.inner.tactile_model.as_ref()
    }

    /// Whether a grasp-type network is loaded (else the geometric rule decides types).
    pub fn has_grasp_type_model(&self) -> bool {
        self.inner.grasp_type_model.is_some()
    }

    /// The built-in hands with the given limits.
    pub fn builtin(limits: Limits) -> Self {
        Self::new(HandCatalog::builtin(), limits)
    }

    /// The built-in hands, the imports and the registered hands of the hands directory. Any
    /// hand that cannot be loaded, or a name used twice, is an error naming it (start-up fails).
    pub fn with_hands(limits: Limits, setup: &HandSetup) -> Result<Self, String> {
        let service = Self::builtin(limits);
        {
            let mut hands = service.hands_mut();
            let add = |loaded: hand_store::LoadedHand, what: &str, hands: &mut Hands| {
                let name = loaded.description.name.clone();
                if hands.catalog.get(&name).is_some() {
                    return Err(format!(
                        "{what}: a hand named '{name}' exists already (built-in or imported twice)"
                    ));
                }
                hands
                    .catalog
                    .insert(loaded.description)
                    .map_err(|e| format!("{what}: {e}"))?;
                hands.models.insert(name, loaded.model);
                Ok(())
            };
            for (name, path) in &setup.imports {
                let what = format!("imported hand '{name}' ({})", path.display());
                hand_store::check_name(name, "name").map_err(|e| format!("{what}: {e}"))?;
                let format = hand_store::ModelFormat::from_path(path).ok_or_else(|| {
                    format!("{what}: unknown model format (give a .xml MJCF or a .urdf file)")
                })?;
                let loaded = hand_store::load_model(path, format, name, &Default::default())
                    .map_err(|e| format!("{what}: {e}"))?;
                add(loaded, &what, &mut hands)?;
            }
            if let Some(dir) = &setup.hands_dir {
                for loaded in hand_store::load_dir(dir)? {
                    let name = loaded.description.name.clone();
                    add(loaded, &format!("registered hand '{name}'"), &mut hands)?;
                    hands.registered.insert(name);
                }
                hands.dir = Some(dir.clone());
            }
        }
        Ok(service)
    }

    fn hands(&self) -> std::sync::RwLockReadGuard<'_, Hands> {
        self.inner
            .hands
            .read()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn hands_mut(&self) -> std::sync::RwLockWriteGuard<'_, Hands> {
        self.inner
            .hands
            .write()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Whether a hand has known kinematics (plans carry joints).
    pub fn has_kinematics(&self, name: &str) -> bool {
        self.hands().models.contains_key(name)
    }

    pub fn limits(&self) -> &Limits {
        &self.inner.limits
    }

    /// All hands of the catalog, by name.
    pub fn list_hands(&self) -> Vec<HandDescription> {
        self.hands().catalog.list().cloned().collect()
    }

    /// One hand; `field` names the name in the error (`name`, `hand_name`).
    pub fn get_hand(&self, name: &str, field: &str) -> Result<HandDescription, ServiceError> {
        let found = self.hands().catalog.get(name).cloned();
        found.ok_or_else(|| ServiceError::NotFound(self.unknown_hand(name, field)))
    }

    /// Registers a hand from its model document and files (issue 6): parsed in a temporary
    /// folder, then moved into the hands directory in one rename and added to the catalog; with
    /// no hands directory configured it lives in memory until the server stops. `replace` may
    /// replace only a hand registered this way. Blocking (file I/O and the workspace sampling):
    /// async callers run it on a blocking thread.
    pub fn register_hand(
        &self,
        upload: HandUpload,
        replace: bool,
    ) -> Result<RegisteredHand, ServiceError> {
        hand_store::check_name(&upload.name, "name")?;
        let upload_bytes = upload.text.len()
            + upload
                .assets
                .iter()
                .map(|a| a.data.len() + a.path.len())
                .sum::<usize>();
        let limit = self.inner.limits.max_message_bytes;
        if upload_bytes > limit {
            return Err(ServiceError::TooLarge(FieldError::new(
                "model",
                format!(
                    "the model and its assets take {upload_bytes} bytes, over the configured limit of {limit} bytes (max_message_bytes)"
                ),
            )));
        }
        let dir = self.hands().dir.clone();
        let check_clash = |hands: &Hands| -> Result<(), ServiceError> {
            if hands.catalog.get(&upload.name).is_some()
                && !(replace && hands.registered.contains(&upload.name))
            {
                let why = if hands.registered.contains(&upload.name) {
                    "a registered hand has this name (set replace to replace it)"
                } else {
                    "a built-in or imported hand has this name"
                };
                return Err(ServiceError::AlreadyExists(FieldError::new(
                    "name",
                    format!("hand '{}' exists: {why}", upload.name),
                )));
            }
            Ok(())
        };
        check_clash(&self.hands())?;
        let to_service = |e: hand_store::RegisterError| match e {
            hand_store::RegisterError::Invalid(f) => ServiceError::InvalidArgument(f),
            hand_store::RegisterError::Io(m) => {
                ServiceError::Internal(format!("cannot store the hand: {m}"))
            }
        };
        // Registrations are serialised by the write lock from here: the check, the rename and
        // the catalog update happen together.
        let parent = dir.clone().unwrap_or_else(std::env::temp_dir);
        let staged = guarded("registering the hand", || {
            hand_store::register(&upload, &parent, None).map_err(to_service)
        })?;
        let mut hands = self.hands_mut();
        check_clash(&hands)?;
        if let Some(dir) = &dir {
            let dest = dir.join(&upload.name);
            let old = dir.join(format!(".tmp-replaced-{}", upload.name));
            if dest.exists() {
                std::fs::rename(&dest, &old).map_err(|e| {
                    ServiceError::Internal(format!("cannot replace the stored hand: {e}"))
                })?;
            }
            let stored = hand_store::register(&upload, dir, Some(&dest)).map_err(to_service);
            match stored {
                Ok(_) => {
                    let _ = std::fs::remove_dir_all(&old);
                }
                Err(e) => {
                    if old.exists() {
                        let _ = std::fs::rename(&old, &dest);
                    }
                    return Err(e);
                }
            }
            hands.registered.insert(upload.name.clone());
        }
        let registered = RegisteredHand {
            description: staged.description.clone(),
            joints: staged
                .model
                .hand
                .tree
                .joints
                .iter()
                .map(|j| j.name.clone())
                .collect(),
            persisted: dir.is_some(),
        };
        hands.catalog.insert(staged.description)?;
        hands.models.insert(upload.name.clone(), staged.model);
        Ok(registered)
    }

    /// Validates a request and plans (Algorithm 4). Blocking and CPU-bound: async callers run it
    /// on a blocking thread. A planner panic becomes `Internal`, so one bad request cannot take
    /// the service down.
    pub fn plan(&self, request: PlanRequest) -> Result<GraspPlan, ServiceError> {
        let output = request.output;
        let (input, perceived) = self.prepare_with_perception(request)?;
        guarded("the planner", || {
            let mut plan = graspd_core::plan(input).map_err(ServiceError::from)?;
            if let Some(p) = perceived {
                p.attach(&mut plan, &output);
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
        let model = self.inner.grasp_type_model.as_deref();
        let mut info = grasp_information(
            &decoded,
            target,
            hints.support_plane,
            model,
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
    fn decode_frame(&self, frame: &RgbdFrame, field: &str) -> Result<DecodedFrame, ServiceError> {
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

    /// The hand of a request and its kinematics, when known.
    fn choose_hand(
        &self,
        choice: HandChoice,
    ) -> Result<(HandDescription, Option<Arc<KinematicModel>>), ServiceError> {
        Ok(match choice {
            HandChoice::Name(name) => {
                let hand = self.hand_by_name(&name)?;
                let model = self.hands().models.get(&name).cloned();
                (hand, model)
            }
            HandChoice::Inline(hand) => {
                hand.validate()
                    .map_err(|e| rename_hand_field(e, "hand_description"))?;
                (*hand, None)
            }
        })
    }

    fn hand_by_name(&self, name: &str) -> Result<HandDescription, ServiceError> {
        let found = self.hands().catalog.get(name).cloned();
        found.ok_or_else(|| ServiceError::InvalidArgument(self.unknown_hand(name, "hand_name")))
    }

    fn unknown_hand(&self, name: &str, field: &str) -> FieldError {
        let names = self.hands().catalog.names().join(", ");
        if name.is_empty() {
            return FieldError::new(field, format!("no hand given (known: {names})"));
        }
        FieldError::new(
            field,
            format!("unknown hand '{}' (known: {names})", name.escape_debug(),),
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Tactile stabilization

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
}

/// A session request in domain terms, as both transports produce it: `config` holds every
/// parameter except the fingers, whose layouts the facade resolves.
#[derive(Debug, Clone, PartialEq)]
pub struct TactileSessionRequest {
    pub fingers: Vec<TactileFingerRequest>,
    pub config: StabilizerConfig,
}

/// An open tactile session: a [`Stabilizer`] holding one of the `max_tactile_sessions` slots,
/// released when this is dropped (e.g. the moment a stream's client disconnects).
#[derive(Debug)]
pub struct TactileSession {
    stabilizer: Stabilizer,
    _slot: SessionSlot,
}

#[derive(Debug)]
struct SessionSlot(Arc<AtomicUsize>);

impl Drop for SessionSlot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

impl TactileSession {
    /// Processes one frame. A frame that does not fit the session (finger or electrode count,
    /// out-of-order timestamp, non-finite value) is `InvalidArgument` naming `frame.…` and
    /// changes nothing.
    pub fn step(&mut self, frame: &Frame) -> Result<FrameResult, ServiceError> {
        let stabilizer = &mut self.stabilizer;
        guarded("the stabilizer", || {
            stabilizer.step(frame).map_err(ServiceError::from)
        })
    }

    /// Frames accepted so far.
    pub fn frames(&self) -> u64 {
        self.stabilizer.frames()
    }

    pub fn config(&self) -> &StabilizerConfig {
        self.stabilizer.config()
    }
}

impl GraspService {
    /// Resolves the layouts and validates the parameters (errors name `session.…`).
    pub fn tactile_config(
        &self,
        request: TactileSessionRequest,
    ) -> Result<StabilizerConfig, ServiceError> {
        let mut config = request.config;
        config.fingers = request
            .fingers
            .into_iter()
            .enumerate()
            .map(|(i, f)| {
                let field = format!("session.fingers[{i}].layout");
                let layout = match f.layout {
                    LayoutChoice::Name(name) => {
                        self.inner.sensors.get(&name).cloned().ok_or_else(|| {
                            FieldError::new(
                                &field,
                                format!(
                                    "unknown layout '{}' (built-in: {}; or give the electrode coordinates)",
                                    name.escape_debug(),
                                    self.inner.sensors.names().join(", ")
                                ),
                            )
                        })?
                    }
                    LayoutChoice::Custom(spec) => SensorLayout::from_spec(spec).map_err(|e| {
                        let rest = e.field.strip_prefix("layout").unwrap_or("");
                        FieldError::new(format!("{field}{rest}"), e.message)
                    })?,
                };
                Ok(FingerConfig {
                    name: f.name,
                    layout,
                    tare: f.tare,
                })
            })
            .collect::<Result<_, FieldError>>()?;
        config.validate()?;
        Ok(config)
    }

    /// Opens a session (one slot of `max_tactile_sessions`; `Exhausted` when none is free).
    pub fn open_tactile_session(
        &self,
        request: TactileSessionRequest,
    ) -> Result<TactileSession, ServiceError> {
        let config = self.tactile_config(request)?;
        let detectors = self.detectors(&config)?;
        let stabilizer = Stabilizer::with_detectors(config, detectors)?;
        let slot = self.take_tactile_slot()?;
        Ok(TactileSession {
            stabilizer,
            _slot: slot,
        })
    }

    /// Runs a whole recorded sequence through a fresh session: one result per frame; errors name
    /// the frame (`frames[12].fingers[0].electrodes`). Holds a session slot while it runs.
    /// Blocking and CPU-bound.
    pub fn analyze_tactile(
        &self,
        request: TactileSessionRequest,
        frames: &[Frame],
    ) -> Result<Vec<FrameResult>, ServiceError> {
        let config = self.tactile_config(request)?;
        let detectors = self.detectors(&config)?;
        let _slot = self.take_tactile_slot()?;
        guarded("the stabilizer", || {
            graspd_core::tactile::analyze_with_detectors(config, detectors, frames)
                .map_err(ServiceError::from)
        })
    }

    /// One detector per finger for a validated config: `model`/`lstm` needs the loaded model
    /// and a session that fits it (errors name the field); the default takes the model when
    /// the session fits it, else the model-free detector.
    fn detectors(
        &self,
        config: &StabilizerConfig,
    ) -> Result<Vec<Box<dyn EventDetector>>, ServiceError> {
        let model_free = |t: ModelFreeThresholds| -> Vec<Box<dyn EventDetector>> {
            config
                .fingers
                .iter()
                .map(|_| {
                    Box::new(graspd_core::tactile::ModelFreeDetector::new(t))
                        as Box<dyn EventDetector>
                })
                .collect()
        };
        let with_model = |m: &Arc<TactileModel>| -> Vec<Box<dyn EventDetector>> {
            config
                .fingers
                .iter()
                .map(|_| Box::new(LstmDetector::new(m.clone())) as Box<dyn EventDetector>)
                .collect()
        };
        let model = self.inner.tactile_model.as_ref();
        match &config.detector {
            DetectorChoice::ModelFree(t) => Ok(model_free(*t)),
            DetectorChoice::Default => Ok(match model {
                Some(m) if tactile_fit(config, m).is_ok() => with_model(m),
                _ => model_free(ModelFreeThresholds::default()),
            }),
            DetectorChoice::Model(name) => {
                let wanted = name.trim().to_ascii_lowercase();
                if wanted != "lstm" && wanted != "model" {
                    return Err(FieldError::new(
                        "session.detector.model",
                        format!(
                            "unknown model '{}'; the learned detector is 'lstm' (or 'model')",
                            name.escape_debug()
                        ),
                    )
                    .into());
                }
                let m = model.ok_or_else(|| {
                    FieldError::new(
                        "session.detector.model",
                        "no tactile model is loaded on this server (start graspd with \
                         --tactile-model FILE, or use model_free)",
                    )
                })?;
                tactile_fit(config, m)?;
                Ok(with_model(m))
            }
        }
    }

    /// Tactile sessions open now.
    pub fn tactile_sessions_open(&self) -> usize {
        self.inner.tactile_sessions.load(Ordering::Acquire)
    }

    fn take_tactile_slot(&self) -> Result<SessionSlot, ServiceError> {
        let max = self.inner.limits.max_tactile_sessions;
        let count = &self.inner.tactile_sessions;
        count
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < max).then_some(n + 1)
            })
            .map_err(|_| {
                ServiceError::Exhausted(format!(
                    "{max} tactile sessions are open, the configured limit (max_tactile_sessions); retry when one has closed"
                ))
            })?;
        Ok(SessionSlot(count.clone()))
    }
}

/// Whether a session fits the tactile model: its window and stride, and every finger's
/// electrode count.
fn tactile_fit(config: &StabilizerConfig, m: &TactileModel) -> Result<(), FieldError> {
    if config.window_length != m.window_length() {
        return Err(FieldError::new(
            "session.window_length",
            format!(
                "the tactile model was trained on windows of {}; got {} (use model_free for \
                 other windows)",
                m.window_length(),
                config.window_length
            ),
        ));
    }
    if config.stride != m.stride() {
        return Err(FieldError::new(
            "session.stride",
            format!(
                "the tactile model was trained with stride {}; got {} (use model_free \
                 for other strides)",
                m.stride(),
                config.stride
            ),
        ));
    }
    for (i, f) in config.fingers.iter().enumerate() {
        if f.layout.electrode_count() != m.electrode_count() {
            return Err(FieldError::new(
                format!("session.fingers[{i}].layout"),
                format!(
                    "layout {} has {} electrodes; the tactile model reads {} (a classic \
                     BioTac); use model_free for this finger's sensor",
                    f.layout.name,
                    f.layout.electrode_count(),
                    m.electrode_count()
                ),
            ));
        }
    }
    Ok(())
}

/// Runs `f`, turning a panic into `Internal` so that one bad input cannot take a task down.
fn guarded<T>(what: &str, f: impl FnOnce() -> Result<T, ServiceError>) -> Result<T, ServiceError> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("unknown panic");
            Err(ServiceError::Internal(format!("{what} failed: {msg}")))
        }
    }
}

/// The core names inline hands `hand.*`; the API calls the field `hand_description`.
fn rename_hand_field(e: FieldError, to: &str) -> ServiceError {
    let field = match e.field.strip_prefix("hand") {
        Some(rest) => format!("{to}{rest}"),
        None => e.field,
    };
    ServiceError::InvalidArgument(FieldError::new(field, e.message))
}

fn finite_point(p: &Point3<f64>, field: &str) -> Result<(), FieldError> {
    if p.coords.iter().all(|v| v.is_finite() && v.abs() <= 1.0e3) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            "coordinates must be finite and within ±1000 m",
        ))
    }
}

fn validate_hints(mut hints: PlanHints, hand: &HandDescription) -> Result<PlanHints, FieldError> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use graspd_core::GraspType;
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

    fn tactile_request(layout: LayoutChoice) -> TactileSessionRequest {
        TactileSessionRequest {
            fingers: vec![TactileFingerRequest {
                name: "th".into(),
                layout,
                tare: TareConfig::pretared(),
            }],
            config: StabilizerConfig::default(),
        }
    }

    #[test]
    fn tactile_sessions_are_limited_and_free_their_slot_on_drop() {
        let s = GraspService::builtin(Limits {
            max_tactile_sessions: 2,
            ..Limits::default()
        });
        let biotac = || tactile_request(LayoutChoice::Name("biotac".into()));
        let a = s.open_tactile_session(biotac()).unwrap();
        let _b = s.open_tactile_session(biotac()).unwrap();
        assert_eq!(s.tactile_sessions_open(), 2);
        let e = s.open_tactile_session(biotac()).unwrap_err();
        assert!(matches!(&e, ServiceError::Exhausted(m) if m.contains("max_tactile_sessions")));
        assert!(matches!(
            s.analyze_tactile(biotac(), &[]),
            Err(ServiceError::Exhausted(_))
        ));
        drop(a);
        assert_eq!(s.tactile_sessions_open(), 1);
        assert!(s.analyze_tactile(biotac(), &[]).unwrap().is_empty());
        assert_eq!(s.tactile_sessions_open(), 1);
        // A refused (invalid) session takes no slot.
        let e = s
            .open_tactile_session(tactile_request(LayoutChoice::Name("nope".into())))
            .unwrap_err();
        assert_eq!(e.field(), Some("session.fingers[0].layout"));
        assert_eq!(s.tactile_sessions_open(), 1);
    }

    #[test]
    fn tactile_layouts_resolve_by_name_or_coordinates() {
        let s = GraspService::builtin(Limits::default());
        let c = s
            .tactile_config(tactile_request(LayoutChoice::Name("biotac_sp".into())))
            .unwrap();
        assert_eq!(c.fingers[0].layout.electrode_count(), 24);
        let spec = |electrodes: Vec<[f64; 2]>| {
            LayoutChoice::Custom(LayoutSpec {
                name: "pad".into(),
                description: String::new(),
                electrodes,
            })
        };
        let c = s
            .tactile_config(tactile_request(spec(vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [0.0, 1.0],
            ])))
            .unwrap();
        assert_eq!(c.fingers[0].layout.electrode_count(), 3);
        let e = s
            .tactile_config(tactile_request(spec(vec![[0.0, 0.0], [f64::NAN, 0.0]])))
            .unwrap_err();
        assert_eq!(e.field(), Some("session.fingers[0].layout.electrodes[1]"));
    }
}
