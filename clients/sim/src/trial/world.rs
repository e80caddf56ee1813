//! The simulated world of one trial: the scene's MuJoCo data, the hand's base and commands, what
//! touches the object, and the hook that runs before every step (the grip reflex). The phases
//! that drive it ([`super`], `closing`, `gravity`) sit above it; it knows none of them.

use crate::camera::{self, Intrinsics, RgbdImage};
use crate::scene::{PARKED, Scene, from_mj, on_table, to_mj};
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Point3};

/// Time a fresh world settles, the object on the table and the hand parked, s.
pub const SETTLE_S: f64 = 0.3;

/// What runs before every simulation step while armed: the grip reflex
/// ([`crate::grip_reflex`]), which reads the contacts and raises the grip.
pub trait BeforeStep {
    fn before_step(&mut self, trial: &mut Trial);
    /// A copy in its present state (the six-direction test restores it with the world's).
    fn boxed_clone(&self) -> Box<dyn BeforeStep>;
}

impl Clone for Box<dyn BeforeStep> {
    fn clone(&self) -> Self {
        self.boxed_clone()
    }
}

/// A trial's state: the scene's data plus the commanded base pose.
pub struct Trial<'a> {
    pub scene: &'a Scene,
    pub data: MjData<&'a MjModel>,
    /// The armed grip reflex, applied before every step.
    pub reflex: Option<Box<dyn BeforeStep>>,
}

impl<'a> Trial<'a> {
    /// Fresh data with object 0 at `place` and the hand parked; steps [`SETTLE_S`].
    pub fn new(scene: &'a Scene, place: [f64; 3]) -> Self {
        Self::with_placements(scene, &[place])
    }

    /// Fresh data with object k at `places[k]` (x, y, yaw on the table; objects beyond them
    /// where the scene put them) and the hand parked; steps [`SETTLE_S`].
    pub fn with_placements(scene: &'a Scene, places: &[[f64; 3]]) -> Self {
        let mut data = scene.model.make_data();
        for (place, &a) in places.iter().zip(&scene.object_qpos) {
            let pose = on_table(place[0], place[1], place[2]);
            let (p, q) = to_mj(&pose);
            data.qpos_mut()[a..a + 3].copy_from_slice(&p);
            data.qpos_mut()[a + 3..a + 7].copy_from_slice(&q);
        }
        // Gravity compensation of the hand, as the arm carrying it would provide: every hand
        // body gets its weight back at its centre of mass.
        let g = scene.model.ffi().opt.gravity;
        for (b, &is_hand) in scene.hand_bodies.iter().enumerate() {
            if is_hand {
                let m = scene.model.body_mass()[b];
                data.xfrc_applied_mut()[b][..3].copy_from_slice(&[-m * g[0], -m * g[1], -m * g[2]]);
            }
        }
        let mut t = Trial {
            scene,
            data,
            reflex: None,
        };
        t.place_base(&from_mj(&PARKED, &[1.0, 0.0, 0.0, 0.0]));
        t.open_hand();
        t.data.forward();
        t.run(SETTLE_S, |_, _| {});
        t
    }

    /// Steps for `seconds`, calling `each(trial, fraction)` before every step.
    pub fn run(&mut self, seconds: f64, mut each: impl FnMut(&mut Self, f64)) {
        let n = (seconds / self.scene.model.ffi().opt.timestep)
            .round()
            .max(1.0) as usize;
        for i in 0..n {
            each(self, (i + 1) as f64 / n as f64);
            if let Some(mut r) = self.reflex.take() {
                r.before_step(self);
                self.reflex = Some(r);
            }
            self.data.step();
        }
    }

    /// Commands the closing actuators to open.
    fn open_hand(&mut self) {
        for &(a, open, _) in &self.scene.closing {
            self.data.ctrl_mut()[a] = open;
        }
    }

    /// Puts the base and its target at `pose` at rest (a jump, before anything touches).
    pub fn place_base(&mut self, pose: &Isometry3<f64>) {
        self.set_base(pose);
        let (p, q) = to_mj(pose);
        let (a, v) = (self.scene.base_qpos, self.scene.base_dof);
        self.data.qpos_mut()[a..a + 3].copy_from_slice(&p);
        self.data.qpos_mut()[a + 3..a + 7].copy_from_slice(&q);
        self.data.qvel_mut()[v..v + 6].fill(0.0);
    }

    /// Sets the base's target (mocap) pose; the weld pulls the base there.
    pub fn set_base(&mut self, pose: &Isometry3<f64>) {
        let (p, q) = to_mj(pose);
        let m = self.scene.mount_mocap;
        self.data.mocap_pos_mut()[m] = p;
        self.data.mocap_quat_mut()[m] = q;
    }

    /// Object 0's position.
    pub fn object_position(&self) -> Point3<f64> {
        let a = self.scene.object_qpos[0];
        let q = &self.data.qpos()[a..a + 3];
        Point3::new(q[0], q[1], q[2])
    }

    /// Object 0's orientation.
    pub fn object_orientation(&self) -> nalgebra::UnitQuaternion<f64> {
        let a = self.scene.object_qpos[0];
        let q = &self.data.qpos()[a + 3..a + 7];
        nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
    }

    /// Contacts between object 0 and a hand body: (index into the contact list, the hand body).
    pub fn hand_contacts_with_object(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let obj = self.scene.object_bodies[0];
        let bodyof = self.scene.model.geom_bodyid();
        self.data
            .contact()
            .iter()
            .enumerate()
            .filter_map(move |(i, c)| {
                let (b1, b2) = (
                    bodyof[c.geom[0] as usize] as usize,
                    bodyof[c.geom[1] as usize] as usize,
                );
                let other = if b1 == obj {
                    b2
                } else if b2 == obj {
                    b1
                } else {
                    return None;
                };
                self.scene.hand_bodies[other].then_some((i, other))
            })
    }

    /// Contacts between a hand body and an object other than object 0 (clutter): (that
    /// object's body, penetration depth in m, 0 for a touch).
    pub fn hand_contacts_with_others(&self) -> Vec<(usize, f64)> {
        let target = self.scene.object_bodies[0];
        let bodyof = self.scene.model.geom_bodyid();
        let mut out = Vec::new();
        for c in self.data.contact() {
            if c.dist > 0.0 {
                continue;
            }
            let (b1, b2) = (
                bodyof[c.geom[0] as usize] as usize,
                bodyof[c.geom[1] as usize] as usize,
            );
            for (obj, other) in [(b1, b2), (b2, b1)] {
                if obj != target
                    && self.scene.object_bodies.contains(&obj)
                    && self.scene.hand_bodies[other]
                {
                    out.push((obj, -c.dist));
                }
            }
        }
        out
    }

    /// Distinct hand bodies within 2 mm of object 0, in contact-list order.
    fn hand_bodies_near_object(&self) -> Vec<usize> {
        let mut bodies: Vec<usize> = Vec::new();
        for (i, b) in self.hand_contacts_with_object() {
            if self.data.contact()[i].dist < 0.002 && !bodies.contains(&b) {
                bodies.push(b);
            }
        }
        bodies
    }

    /// Names (without the hand prefix) of the hand bodies touching object 0.
    pub fn hand_body_names_touching(&self) -> Vec<String> {
        let m = &self.scene.model;
        self.hand_bodies_near_object()
            .into_iter()
            .map(|b| {
                let n = m.id_to_name(MjtObjBase::mjOBJ_BODY, b).unwrap_or_default();
                n.strip_prefix(crate::scene::HAND_PREFIX)
                    .unwrap_or(n)
                    .to_string()
            })
            .collect()
    }

    /// Object 0's centre of mass.
    pub fn object_com(&self) -> Point3<f64> {
        Point3::from(self.data.xipos()[self.scene.object_bodies[0]])
    }

    /// Whether object 0 touches the table.
    pub fn object_touches_table(&self) -> bool {
        let obj = self.scene.object_bodies[0];
        let bodyof = self.scene.model.geom_bodyid();
        self.data.contact().iter().any(|c| {
            let (g1, g2) = (c.geom[0] as usize, c.geom[1] as usize);
            c.dist < 0.001
                && ((g1 == self.scene.table_geom && bodyof[g2] as usize == obj)
                    || (g2 == self.scene.table_geom && bodyof[g1] as usize == obj))
        })
    }

    /// Distinct hand bodies in contact with object 0.
    pub fn hand_bodies_touching(&self) -> usize {
        self.hand_bodies_near_object().len()
    }

    /// Deepest penetration of a hand body into object 0, m (0 when none touches it).
    pub fn deepest_object_penetration(&self) -> f64 {
        self.hand_contacts_with_object()
            .map(|(i, _)| -self.data.contact()[i].dist)
            .fold(0.0, f64::max)
    }

    /// Deepest penetration of a hand geom into the table, m (0 when none touches).
    pub fn deepest_table_penetration(&self) -> f64 {
        let table = self.scene.table_geom;
        self.data
            .contact()
            .iter()
            .filter(|c| {
                let (g1, g2) = (c.geom[0] as usize, c.geom[1] as usize);
                (g1 == table && self.scene.is_hand_geom(g2))
                    || (g2 == table && self.scene.is_hand_geom(g1))
            })
            .map(|c| -c.dist)
            .fold(0.0, f64::max)
    }

    /// Renders the current state.
    pub fn render(&mut self, intr: Intrinsics, camera: Isometry3<f64>) -> RgbdImage {
        self.data.forward();
        camera::render(self.scene, &mut self.data, intr, camera)
    }

    /// Every actuator's command at `joints` (a position servo's equilibrium there,
    /// `-bias₁·length/gain₀`), within its control range.
    pub(crate) fn planned_commands(&mut self, joints: &[(String, f64)]) -> Vec<f64> {
        let saved: Vec<f64> = self.data.qpos().to_vec();
        self.set_hand_joints(joints);
        self.data.forward();
        let m = &self.scene.model;
        let len = self.data.actuator_length();
        let cmd: Vec<f64> = (0..m.ffi().nu as usize)
            .map(|a| crate::hand::servo_command(m, a, len[a]))
            .collect();
        self.data.qpos_mut().copy_from_slice(&saved);
        self.data.forward();
        cmd
    }

    /// Sets the hand's joints by name (names as graspd lists them, i.e. the model's).
    pub(crate) fn set_hand_joints(&mut self, joints: &[(String, f64)]) {
        for (adr, name) in &self.scene.hand_joints {
            if let Some((_, v)) = joints.iter().find(|(n, _)| n == name) {
                self.data.qpos_mut()[*adr] = *v;
            }
        }
    }
}
