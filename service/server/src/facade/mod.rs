//! The one facade that both transports call: the hand catalog, the configured limits, and the
//! validation of a plan request before it reaches the planner. Plain Rust and synchronous (no
//! tonic, axum, tokio or proto types), so it also serves as the library entry point.
//!
//! One file per concern: [`validate`] (the request rules the facade owns; the options' ranges
//! are `PlannerOptions::validate`'s), [`plan`], [`reach`] (reaching trajectories), [`hands`] (catalog and registration),
//! [`tactile`] (sessions and analysis), [`calibrations`] (tactile calibrations: fit, store,
//! name). The requests and answers it takes and gives, its `Limits` (configured bounds, the CPU
//! cap on options included) and its `ServiceError` are `graspd-api`'s, so that the clients
//! build the same ones.

use crate::hand_store;
use graspd_core::HandCatalog;
use graspd_core::perception::{GraspTypeModel, RecognitionModel};
use graspd_core::planning::KinematicModel;
use graspd_core::planning::grasp_quality::GraspQualityModel;
use graspd_core::tactile::{SensorCatalog, TactileModel};
use std::collections::{BTreeMap, BTreeSet};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::atomic::AtomicUsize;
use std::sync::{Arc, RwLock};

mod calibrations;
mod hands;
mod plan;
mod reach;
mod tactile;
mod validate;

pub use calibrations::{CalibrationInfo, CalibrationUpload, RecordingUpload};
pub use graspd_api::ServiceError;
pub use graspd_api::limits::{
    DEFAULT_MAX_ITERATIONS, DEFAULT_MAX_TACTILE_SESSIONS, DEFAULT_MAX_VIEWS, Limits,
    QUEUED_PLANS_PER_PLANNER,
};
pub use graspd_api::request::{
    HandChoice, HandSynergies, ImageHints, OutputOptions, PlanRequest, PlanSource,
};
pub use hands::{HandSetup, RegisteredHand};
pub use tactile::{LayoutChoice, TactileFingerRequest, TactileSession, TactileSessionRequest};

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
    /// The recogniser of `hints.object` (§3.2.1), when loaded.
    recogniser: Option<Arc<RecognitionModel>>,
    /// The learned parallel-jaw quality of `options.mode = learned_quality` (§3.2.2), when
    /// loaded.
    grasp_quality: Option<Arc<GraspQualityModel>>,
    /// Tactile calibrations by name (issue 16).
    calibrations: RwLock<calibrations::Calibrations>,
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
    /// Posture synergies fitted so far, with the model each was fitted to (a replaced hand's
    /// model is another, so its old synergies are not served).
    synergies: BTreeMap<String, (Arc<KinematicModel>, Arc<HandSynergies>)>,
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
                recogniser: None,
                grasp_quality: None,
                calibrations: RwLock::default(),
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

    /// Sets the recogniser that serves `hints.object` (at start, before the service is cloned).
    pub fn with_recogniser(mut self, model: Arc<RecognitionModel>) -> Self {
        Arc::get_mut(&mut self.inner)
            .expect("the model is set at start, before the service is shared")
            .recogniser = Some(model);
        self
    }

    /// Sets the grasp-quality network of `options.mode = learned_quality` (at start, before the
    /// service is cloned).
    pub fn with_grasp_quality(mut self, model: Arc<GraspQualityModel>) -> Self {
        Arc::get_mut(&mut self.inner)
            .expect("the model is set at start, before the service is shared")
            .grasp_quality = Some(model);
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

    pub fn limits(&self) -> &Limits {
        &self.inner.limits
    }
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
