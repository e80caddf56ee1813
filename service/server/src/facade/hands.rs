//! The hands: the catalog, registration at run time, and the hand a request names.

use super::validate::rename_hand_field;
use super::{GraspService, HandChoice, Hands, ServiceError, guarded};
use crate::hand_store::{self, HandUpload};
use graspd_api::request::HandSynergies;
pub use graspd_api::request::RegisteredHand;
use graspd_core::hand::PostureSynergies;
use graspd_core::planning::KinematicModel;
use graspd_core::planning::synergy_postures::synergy_postures;
use graspd_core::{FieldError, HandDescription};
use std::path::PathBuf;
use std::sync::Arc;

/// The planner's seed for the postures a hand's synergies are fitted to: one fixed seed, so that
/// a hand has one answer.
pub const SYNERGY_SEED: u64 = 0;

/// Hands to load at start (configuration).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HandSetup {
    /// Registered hands persist here and are loaded again at start.
    pub hands_dir: Option<PathBuf>,
    /// `(name, model file)` pairs read at start (MJCF `.xml` or URDF `.urdf`).
    pub imports: Vec<(String, PathBuf)>,
}

impl GraspService {
    /// Whether a hand has known kinematics (plans carry joints).
    pub fn has_kinematics(&self, name: &str) -> bool {
        self.hands().models.contains_key(name)
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

    /// A hand's posture synergies (issue 19, dissertation §7.3): fitted on the first request to
    /// the planner's own grasp postures for the hand over generated objects
    /// (`planning::synergy_postures`; 2.5 s for the Shadow on one core, release) and kept until the
    /// hand is replaced. Needs the hand's kinematics: a built-in or described hand has no joints.
    /// Blocking: async callers run it on a blocking thread.
    pub fn hand_synergies(&self, name: &str) -> Result<Arc<HandSynergies>, ServiceError> {
        let (model, cached) = {
            let hands = self.hands();
            let model = hands.models.get(name).cloned();
            let cached = hands
                .synergies
                .get(name)
                .filter(|(m, _)| model.as_ref().is_some_and(|x| Arc::ptr_eq(x, m)))
                .map(|(_, s)| s.clone());
            (model, cached)
        };
        if let Some(s) = cached {
            return Ok(s);
        }
        let Some(model) = model else {
            self.get_hand(name, "name")?;
            return Err(ServiceError::InvalidArgument(FieldError::new(
                "name",
                format!(
                    "hand '{}' has no kinematics: synergies are a PCA of joint postures, and a built-in or described hand has no joints (register its MJCF or URDF with POST /v1/hands)",
                    name.escape_debug()
                ),
            )));
        };
        let fitted = guarded("fitting the posture synergies", || {
            let (joints, postures, plans) = synergy_postures(&model, SYNERGY_SEED)?;
            let synergies = PostureSynergies::fit(joints, &postures).map_err(|e| {
                ServiceError::InvalidArgument(FieldError::new(
                    "name",
                    format!(
                        "{} of {plans} plans for hand '{}' were feasible, too few for its posture space ({})",
                        postures.len(),
                        name.escape_debug(),
                        e.message
                    ),
                ))
            })?;
            Ok(HandSynergies {
                hand: name.to_string(),
                synergies,
                plans,
                seed: SYNERGY_SEED,
            })
        })?;
        let fitted = Arc::new(fitted);
        self.hands_mut()
            .synergies
            .insert(name.to_string(), (model, fitted.clone()));
        Ok(fitted)
    }

    /// The hand of a request and its kinematics, when known.
    pub(super) fn choose_hand(
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

    pub(super) fn hand_by_name(&self, name: &str) -> Result<HandDescription, ServiceError> {
        let found = self.hands().catalog.get(name).cloned();
        found.ok_or_else(|| ServiceError::InvalidArgument(self.unknown_hand(name, "hand_name")))
    }

    pub(super) fn unknown_hand(&self, name: &str, field: &str) -> FieldError {
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
