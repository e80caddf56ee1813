//! The tactile closed loop in simulation (issue 7 item 4; method.md §5, Algorithm 5): simulated
//! BioTac readings from the pads' contacts are streamed to graspd's `Stabilize`, and its desired
//! force f_d (Eq 6.8, 6.9) is what the gripper's force loop tracks; a disturbance protocol
//! compares it with a constant-force baseline.
//!
//! # Simulated sensor ([`SimBiotac`]), 100 Hz, already tared (`pretared`, rising electrodes)
//! - pdc = [`PDC_PER_N`] · F_n, with F_n the pad's normal contact force on the object;
//! - electrode i = [`ELECTRODE_PER_N`] · F_n · exp(−d_i² / 2σ²), d_i the electrode's distance
//!   from the pressed spot (σ = [`PATCH_SIGMA_MM`]): the centre of the BioTac layout where the
//!   pad first touched the object, then moved as the contact point moves on the pad (its
//!   displacement in the pad's frame, across the contact normal, in mm) — an object rolling
//!   over the pad or sliding along it moves the spot;
//! - pac: 22 samples of white noise with standard deviation [`PAC_PER_M_S`] · v_slip, v_slip the
//!   tangential speed of the object relative to the pad at the contact (sliding excites the
//!   skin; graspd's model-free detector reads the vibration);
//! - every channel gets [`NOISE_COUNTS`] of Gaussian noise; tdc = tac = 0.
//!   These gains are chosen, not calibrated: a touch of 0.5 N crosses the model-free detector's
//!   15-count pdc threshold and 5 mm/s of sliding its 10-count vibration threshold.
//!
//! # Grip force loop
//! The gripper's closing actuators are driven as force sources: command = the actuator force F_t
//! (from the servo's affine law, ctrl = (F_t − b₁·length − b₂·velocity)/g₀), and F_t follows
//! dF_t/dt = [`FORCE_LOOP_GAIN`] · (F_cmd − F̄_n) with F̄_n the pads' mean normal force: the
//! hand's own low-level force control. F_cmd is graspd's f_d (the largest over the fingers) in
//! the stabilized runs and the constant f0 in the baseline.
//!
//! # Disturbance protocol ([`Disturbance`])
//! Plan and approach as in a trial; close under force control at f0 = `safety` · m·g / (2 μ)
//! (μ: the pads' friction, two pads); lift 10 cm, hold 0.5 s; then added mass: a downward force
//! on the object's centre of mass that rises linearly to `pulse` · m·g in `pulse_s` and stays
//! for another `pulse_s`; released, hold 1 s more. Held = off the
//! table, touching the hand, centre of mass ≥ 3 cm above its start. In the stabilized run the
//! session uses f0 as above, δf_s = f0 (slip doubles the force), δf_m = 0, the model-free
//! detector, and the default window (l = 32, k = 3); f_max = `max_force` · f0, and the latch
//! and the centroid slip as [`Disturbance`] asks (`make sim-stabilize` runs both ways).

use crate::SimError;
use crate::hand::SimHand;
use crate::scene::Scene;
use crate::service::Service;
use crate::trial::{
    LIFT_M, LIFT_S, LIFTED_M, Motion, Trial, TrialOptions, TrialRecord, placement,
    pre_grasp_and_approach,
};
use graspd_core::tactile::layout::SensorLayout;
use graspd_proto::v1 as pb;
use mujoco_rs::prelude::*;
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use serde::Serialize;

pub const PDC_PER_N: f64 = 30.0;
pub const ELECTRODE_PER_N: f64 = 25.0;
pub const PATCH_SIGMA_MM: f64 = 4.0;
pub const PAC_PER_M_S: f64 = 2000.0;
pub const NOISE_COUNTS: f64 = 1.0;
/// Pac samples per frame (a BioTac at 2.2 kHz and 100 Hz frames).
pub const PAC_SAMPLES: usize = 22;
/// Frame period, s.
pub const FRAME_S: f64 = 0.01;
/// Gain of the grip force loop, actuator newtons per newton of pad-force error per second.
pub const FORCE_LOOP_GAIN: f64 = 20.0;

/// A simulated, pre-tared BioTac on one pad.
pub struct SimBiotac {
    electrodes: Vec<[f64; 2]>,
    /// The layout's centre, mm: where the spot is before the contact moves.
    centre: [f64; 2],
    rng: rand_chacha::ChaCha8Rng,
}

impl SimBiotac {
    pub fn new(layout: &SensorLayout, seed: u64) -> Self {
        let n = layout.electrodes.len() as f64;
        let centre = layout
            .electrodes
            .iter()
            .fold([0.0, 0.0], |a, e| [a[0] + e[0] / n, a[1] + e[1] / n]);
        SimBiotac {
            electrodes: layout.electrodes.clone(),
            centre,
            rng: rand_chacha::ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// Each electrode's share of the normal force with the spot `moved` (mm) off the centre.
    fn weights(&self, moved: [f64; 2]) -> Vec<f64> {
        let c = [self.centre[0] + moved[0], self.centre[1] + moved[1]];
        self.electrodes
            .iter()
            .map(|e| {
                let d2 = (e[0] - c[0]).powi(2) + (e[1] - c[1]).powi(2);
                (-d2 / (2.0 * PATCH_SIGMA_MM * PATCH_SIGMA_MM)).exp()
            })
            .collect()
    }

    /// A standard normal sample (Box–Muller).
    fn gauss(&mut self) -> f64 {
        let u1: f64 = self.rng.random_range(f64::EPSILON..1.0);
        let u2: f64 = self.rng.random();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// One frame for normal force `normal` (N), slip speed `slip` (m/s) and the spot `moved`
    /// (mm) from where the pad first touched.
    pub fn reading(&mut self, normal: f64, slip: f64, moved: [f64; 2]) -> pb::FingerReading {
        let pdc = PDC_PER_N * normal + NOISE_COUNTS * self.gauss();
        let electrodes = self
            .weights(moved)
            .into_iter()
            .map(|w| ELECTRODE_PER_N * normal * w + NOISE_COUNTS * self.gauss())
            .collect();
        let pac = (0..PAC_SAMPLES)
            .map(|_| (PAC_PER_M_S * slip + NOISE_COUNTS) * self.gauss())
            .collect();
        pb::FingerReading {
            pdc,
            pac,
            tdc: 0.0,
            tac: 0.0,
            electrodes,
        }
    }
}

/// The disturbance protocol's parameters (see the module documentation).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Disturbance {
    /// Static safety factor of the initial grip force f0.
    pub safety: f64,
    /// Downward pulse, in object weights.
    pub pulse: f64,
    pub pulse_s: f64,
    /// δf_s of the stabilized session, in units of f0.
    pub slip_gain: f64,
    /// f_max of the stabilized session, in units of f0 (default 1 + slip_gain).
    pub max_force: f64,
    /// The session's latched slip (`latch_slip`, a deviation from Eq 6.9).
    pub latch_slip: bool,
    /// The session's slip from the contact centroid's motion, mm/s (`centroid_slip_mm_s`).
    pub centroid_slip_mm_s: Option<f64>,
    /// The pads' sensors as electrodes-only fingers (`electrodes_only`: no pac, pdc or thermal
    /// channel reaches graspd).
    pub electrodes_only: bool,
}

impl Default for Disturbance {
    fn default() -> Self {
        Disturbance {
            safety: 1.5,
            pulse: 1.0,
            pulse_s: 0.5,
            slip_gain: 1.0,
            max_force: 2.0,
            latch_slip: false,
            centroid_slip_mm_s: None,
            electrodes_only: false,
        }
    }
}

/// One disturbance trial.
#[derive(Debug, Clone, Serialize)]
pub struct DisturbanceRecord {
    pub object: String,
    pub seed: u64,
    pub stabilized: bool,
    /// Whether the trial got to the disturbance (plan, approach and lift worked).
    pub reached_pulse: bool,
    pub held: bool,
    pub detail: String,
    /// f0, N.
    pub f0: f64,
    /// Largest commanded grip force, N.
    pub max_command: f64,
    /// Frames graspd called slip (any finger), in all and before the pulse.
    pub slip_frames: usize,
    pub slip_frames_before_pulse: usize,
    /// How far the object slid down in the hand during and after the pulse, mm.
    pub slid_mm: f64,
}

/// What pad body `pad` feels: the normal force on the object, the slip speed at the contact,
/// and (while it touches) the force-weighted contact point and normal in the pad's frame.
struct PadState {
    normal: f64,
    slip: f64,
    contact: Option<(Vector3<f64>, Vector3<f64>)>,
}

fn pad_state(trial: &Trial, pad: usize) -> PadState {
    let obj = trial.scene.object_bodies[0];
    let (mut normal, mut slip) = (0.0, 0.0f64);
    let (mut at, mut n) = (Vector3::zeros(), Vector3::zeros());
    for (i, _) in trial.hand_contacts_with_object().filter(|&(_, b)| b == pad) {
        let f = trial.data.contact_force(i)[0].max(0.0);
        normal += f;
        slip = slip.max(crate::grip_reflex::contact_sliding(trial, i, obj, pad));
        let c = &trial.data.contact()[i];
        at += f * Vector3::from(c.pos);
        n += f * Vector3::new(c.frame[0], c.frame[1], c.frame[2]);
    }
    let contact = (normal > 1e-9).then(|| {
        let x = trial.data.xpos()[pad];
        let m = trial.data.xmat()[pad];
        let r = nalgebra::Matrix3::from_row_slice(&m[..]);
        let local = r.transpose() * (at / normal - Vector3::new(x[0], x[1], x[2]));
        (local, (r.transpose() * n).normalize())
    });
    PadState {
        normal,
        slip,
        contact,
    }
}

/// Where the pressed spot has moved on a pad since it first touched, mm: the contact point's
/// displacement in the pad's frame across the first contact's normal.
#[derive(Default)]
struct SpotTrack {
    first: Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)>,
}

impl SpotTrack {
    fn moved(&mut self, contact: Option<(Vector3<f64>, Vector3<f64>)>) -> [f64; 2] {
        let Some((p, n)) = contact else {
            return [0.0, 0.0];
        };
        let (p0, u, v) = *self.first.get_or_insert_with(|| {
            let u = n
                .cross(&Vector3::x())
                .try_normalize(1e-6)
                .unwrap_or_else(|| n.cross(&Vector3::y()).normalize());
            (p, u, n.cross(&u))
        });
        let d = (p - p0) * 1e3;
        [d.dot(&u), d.dot(&v)]
    }
}

/// Drives the closing actuators as force sources toward actuator force `ft`.
fn apply_actuator_force(trial: &mut Trial, ft: f64) {
    let scene = trial.scene;
    let m = &scene.model;
    let (gain, bias, range) = (
        m.actuator_gainprm(),
        m.actuator_biasprm(),
        m.actuator_ctrlrange(),
    );
    for &(a, open, closed) in &scene.closing {
        let (len, vel) = (
            trial.data.actuator_length()[a],
            trial.data.actuator_velocity()[a],
        );
        let g = gain[a][0];
        // The force acts toward closed: negative when the span runs downward.
        let f = if closed < open { -ft } else { ft };
        let mut c = if g.abs() > 1e-12 {
            (f - bias[a][1] * len - bias[a][2] * vel) / g
        } else {
            closed
        };
        if range[a][0] < range[a][1] {
            c = c.clamp(range[a][0], range[a][1]);
        }
        trial.data.ctrl_mut()[a] = c;
    }
}

/// The largest actuator force the closing actuators can exert, N.
fn max_actuator_force(scene: &Scene) -> f64 {
    let fr = scene.model.actuator_forcerange();
    scene
        .closing
        .iter()
        .map(|&(a, _, _)| {
            let f = fr[a][1];
            if f > 0.0 { f } else { 100.0 }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Runs one disturbance trial of `hand` (which needs `tactile_bodies`) on object 0.
#[allow(clippy::too_many_arguments)]
pub fn run_disturbance_trial(
    scene: &Scene,
    hand: &SimHand,
    object: &str,
    service: &Service,
    seed: u64,
    opts: &TrialOptions,
    dist: &Disturbance,
    stabilized: bool,
) -> Result<DisturbanceRecord, SimError> {
    let pads: Vec<usize> = hand
        .tactile_bodies
        .iter()
        .map(|b| {
            scene
                .model
                .name_to_id(
                    MjtObjBase::mjOBJ_BODY,
                    &format!("{}{b}", crate::scene::HAND_PREFIX),
                )
                .ok_or_else(|| SimError::Input(format!("hands: no tactile body `{b}`")))
        })
        .collect::<Result<_, _>>()?;
    if pads.is_empty() {
        return Err(SimError::Input(format!(
            "hands: {} has no tactile_bodies",
            hand.name
        )));
    }
    let mu = hand.pad_friction.unwrap_or(0.6);
    // The closed-loop run keeps its measured placements (±5 cm).
    let place = placement(seed, 0.05);
    let mut trial = Trial::new(scene, place);
    let start = trial.object_position();
    let mass = scene.model.body_mass()[scene.object_bodies[0]];
    let weight = mass * 9.81;
    let f0 = dist.safety * weight / (pads.len() as f64 * mu);
    let mut out = DisturbanceRecord {
        object: object.to_string(),
        seed,
        stabilized,
        reached_pulse: false,
        held: false,
        detail: String::new(),
        f0,
        max_command: f0,
        slip_frames: 0,
        slip_frames_before_pulse: 0,
        slid_mm: 0.0,
    };
    let image = trial.render(opts.intrinsics, opts.camera);
    let plan = match service.plan(hand, &image, &[], None, seed, &Default::default()) {
        Ok(p) => p,
        Err(s) => {
            out.detail = format!("no plan: {}", s.message());
            return Ok(out);
        }
    };
    let mut rec = TrialRecord::empty(hand, object, seed, place);
    let approached =
        match pre_grasp_and_approach(&mut trial, &plan, start, Motion::Straight, &mut rec) {
            Ok(a) => a,
            Err(o) => {
                out.detail = format!("{}: {}", o.name(), rec.detail);
                return Ok(out);
            }
        };
    let mut stream = if stabilized {
        let layout = pb::TactileFinger {
            name: String::new(),
            layout: Some(pb::tactile_finger::Layout::LayoutName("biotac".into())),
            tare: Some(pb::TareSettings {
                pretared: true,
                electrode_polarity: pb::ElectrodePolarity::Rising as i32,
                ..Default::default()
            }),
            electrodes_only: dist.electrodes_only,
            calibration: None,
        };
        Some(
            service.stabilize(pb::TactileSession {
                fingers: hand
                    .tactile_bodies
                    .iter()
                    .map(|b| pb::TactileFinger {
                        name: b.clone(),
                        ..layout.clone()
                    })
                    .collect(),
                f0: Some(f0),
                delta_material: Some(0.0),
                delta_slip: Some(dist.slip_gain * f0),
                f_min: Some(0.0),
                f_max: Some(dist.max_force * f0),
                latch_slip: Some(dist.latch_slip),
                centroid_slip_mm_s: dist.centroid_slip_mm_s,
                detector: Some(pb::TactileDetector {
                    kind: Some(pb::tactile_detector::Kind::ModelFree(Default::default())),
                }),
                ..Default::default()
            })?,
        )
    } else {
        None
    };
    let layout = SensorLayout::biotac();
    let mut sensors: Vec<SimBiotac> = (0..pads.len())
        .map(|k| SimBiotac::new(&layout, seed * 31 + k as u64))
        .collect();
    let mut spots: Vec<SpotTrack> = pads.iter().map(|_| SpotTrack::default()).collect();
    let dt = scene.model.ffi().opt.timestep;
    let frame_steps = (FRAME_S / dt).round() as usize;
    let ft_max = max_actuator_force(scene);
    let mut ft = 0.0;
    let mut command = f0;
    let mut step_no = 0usize;
    let mut error: Option<SimError> = None;
    let root = approached.root;
    let obj = scene.object_bodies[0];
    // One control step: sensors and graspd at 100 Hz, the force loop every step.
    let mut control = |t: &mut Trial, out: &mut DisturbanceRecord| {
        let states: Vec<PadState> = pads.iter().map(|&p| pad_state(t, p)).collect();
        if step_no.is_multiple_of(frame_steps)
            && let Some(s) = stream.as_mut()
        {
            let frame = pb::TactileFrame {
                timestamp: t.data.time(),
                fingers: states
                    .iter()
                    .zip(sensors.iter_mut().zip(spots.iter_mut()))
                    .map(|(s, (sensor, spot))| {
                        sensor.reading(s.normal, s.slip, spot.moved(s.contact))
                    })
                    .collect(),
            };
            match s.frame(frame) {
                Ok(sp) => {
                    if sp
                        .fingers
                        .iter()
                        .any(|f| f.event == pb::ContactEvent::Slip as i32)
                    {
                        out.slip_frames += 1;
                    }
                    command = sp
                        .fingers
                        .iter()
                        .map(|f| f.desired_force)
                        .fold(f0, f64::max);
                    out.max_command = out.max_command.max(command);
                }
                Err(e) => {
                    if error.is_none() {
                        error = Some(e);
                    }
                }
            }
        }
        step_no += 1;
        let mean = states.iter().map(|s| s.normal).sum::<f64>() / states.len() as f64;
        ft = (ft + FORCE_LOOP_GAIN * (command - mean) * dt).clamp(0.0, ft_max);
        apply_actuator_force(t, ft);
    };
    // Close under force control, then lift and hold.
    trial.run(0.8, |t, _| control(t, &mut out));
    trial.run(LIFT_S, |t, f| {
        control(t, &mut out);
        let up = nalgebra::Translation3::new(0.0, 0.0, LIFT_M * f * f * (3.0 - 2.0 * f));
        t.set_base(&(up * root));
    });
    trial.run(0.5, |t, _| control(t, &mut out));
    let held = |t: &Trial| {
        t.object_com().z - approached.start_com.z >= LIFTED_M
            && !t.object_touches_table()
            && t.hand_bodies_touching() >= 1
    };
    if !held(&trial) {
        out.detail = "not held before the disturbance".into();
        return error.map_or(Ok(out), Err);
    }
    out.reached_pulse = true;
    out.slip_frames_before_pulse = out.slip_frames;
    let base_z = |t: &Trial| crate::trial::base_pose(t).translation.vector.z;
    let rel0 = trial.object_com().z - base_z(&trial);
    // Added mass: the extra load rises linearly to its full value in pulse_s and stays another
    // pulse_s (a step would drop the object within one 10 ms frame, before any sensor could
    // tell).
    trial.run(2.0 * dist.pulse_s, |t, f| {
        t.data.xfrc_applied_mut()[obj][2] = -dist.pulse * weight * (2.0 * f).min(1.0);
        control(t, &mut out);
    });
    trial.data.xfrc_applied_mut()[obj][2] = 0.0;
    trial.run(1.0, |t, _| control(t, &mut out));
    if let Some(e) = error {
        return Err(e);
    }
    out.slid_mm = ((rel0 - (trial.object_com().z - base_z(&trial))) * 1e3).max(0.0);
    out.held = held(&trial);
    if !out.held {
        out.detail = "dropped under the disturbance".into();
    }
    Ok(out)
}

/// The whole protocol: every object × trial once stabilized and once at constant force; writes
/// `stabilize.json` and `stabilize.md` under `out` and returns the Markdown.
#[allow(clippy::too_many_arguments)]
pub fn run_protocol(
    hand: &SimHand,
    objects: &[String],
    trials: usize,
    seed: u64,
    dist: &Disturbance,
    objects_dir: &std::path::Path,
    service: &Service,
    opts: &TrialOptions,
    out: &std::path::Path,
) -> Result<String, SimError> {
    use std::fmt::Write as _;
    let bar = indicatif::ProgressBar::new((objects.len() * trials * 2) as u64);
    let mut records = Vec::new();
    for name in objects {
        let obj = crate::object::SimObject::load(objects_dir, name)?;
        let scene = Scene::build(hand, &[(&obj, crate::scene::on_table(0.0, 0.0, 0.0))])?;
        for i in 0..trials {
            for stabilized in [false, true] {
                let r = run_disturbance_trial(
                    &scene,
                    hand,
                    name,
                    service,
                    seed + i as u64,
                    opts,
                    dist,
                    stabilized,
                )?;
                bar.inc(1);
                records.push(r);
            }
        }
    }
    bar.finish_and_clear();
    // Paired: a trial counts when both runs got to the disturbance (the stabilized run also
    // grips harder during the lift when it feels slip, so it gets there more often).
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| object | both reached the load | constant force: held | stabilized: held | \
         stabilized: frames with slip | stabilized: peak f_d / f0 | slid in the hand, mm \
         (constant / stabilized) |"
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|");
    let (mut tb, mut ts, mut tn) = (0, 0, 0);
    for name in objects {
        let pairs: Vec<(&DisturbanceRecord, &DisturbanceRecord)> = records
            .chunks(2)
            .filter(|p| &p[0].object == name && p[0].reached_pulse && p[1].reached_pulse)
            .map(|p| (&p[0], &p[1]))
            .collect();
        let n = pairs.len();
        let hb = pairs.iter().filter(|p| p.0.held).count();
        let hs = pairs.iter().filter(|p| p.1.held).count();
        let mean = |f: &dyn Fn(&(&DisturbanceRecord, &DisturbanceRecord)) -> f64| {
            pairs.iter().map(f).sum::<f64>() / n.max(1) as f64
        };
        if n == 0 {
            let _ = writeln!(
                md,
                "| {} | 0/{trials} | – | – | – | – | – |",
                name.replace('_', " ")
            );
            continue;
        }
        let _ = writeln!(
            md,
            "| {} | {n}/{trials} | {hb}/{n} | {hs}/{n} | {:.0} | {:.2} | {:.0} / {:.0} |",
            name.replace('_', " "),
            mean(&|p| p.1.slip_frames as f64),
            mean(&|p| p.1.max_command / p.1.f0),
            mean(&|p| p.0.slid_mm),
            mean(&|p| p.1.slid_mm),
        );
        tb += hb;
        ts += hs;
        tn += n;
    }
    let _ = writeln!(
        md,
        "| **all** | {tn} | **{tb}/{tn}** ({:.0} % dropped) | **{ts}/{tn}** ({:.0} % dropped) | | | |",
        100.0 * (tn - tb) as f64 / tn.max(1) as f64,
        100.0 * (tn - ts) as f64 / tn.max(1) as f64
    );
    let _ = writeln!(
        md,
        "\nHand {}, seeds {}..{}, grip f0 = {} × m·g / (2 μ), added load rising to {} × m·g in \
         {} s and staying {} s, δf_s = {} · f0, f_max = {} · f0, {}, {}, model-free detector.",
        hand.label,
        seed,
        seed + trials as u64,
        dist.safety,
        dist.pulse,
        dist.pulse_s,
        dist.pulse_s,
        dist.slip_gain,
        dist.max_force,
        if dist.latch_slip {
            "slip latched (each slip episode, and each further 0.1 s of slip, adds δf_s until contact is lost)"
        } else {
            "Eq 6.9 as printed (no latch)"
        },
        match (dist.centroid_slip_mm_s, dist.electrodes_only) {
            (v, true) => format!(
                "electrodes-only sensors (slip from the contact centroid moving faster than {} mm/s)",
                v.unwrap_or(graspd_core::tactile::stabilizer::ELECTRODE_SLIP_MM_S)
            ),
            (Some(v), false) => {
                format!("slip also from the contact centroid moving faster than {v} mm/s")
            }
            (None, false) => "slip from the detector alone".to_string(),
        }
    );
    std::fs::create_dir_all(out)
        .map_err(|e| SimError::Input(format!("--out {}: {e}", out.display())))?;
    let json = serde_json::json!({ "disturbance": dist, "records": records });
    std::fs::write(
        out.join("stabilize.json"),
        serde_json::to_string_pretty(&json).unwrap_or_default(),
    )
    .and_then(|_| std::fs::write(out.join("stabilize.md"), &md))
    .map_err(|e| SimError::Input(format!("--out: {e}")))?;
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sensor model's gains, checked on its own readings: pdc and the central electrodes
    /// scale with the normal force, the electrodes' centroid moves with the spot, pac's spread
    /// with the slip speed.
    #[test]
    fn simulated_biotac_scales_with_force_and_slip() {
        let layout = SensorLayout::biotac();
        let mut s = SimBiotac::new(&layout, 7);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let pdc: Vec<f64> = (0..400)
            .map(|_| s.reading(2.0, 0.0, [0.0, 0.0]).pdc)
            .collect();
        assert!((mean(&pdc) - 2.0 * PDC_PER_N).abs() < 0.3, "{}", mean(&pdc));
        let r = s.reading(2.0, 0.0, [0.0, 0.0]);
        assert_eq!(r.electrodes.len(), layout.electrodes.len());
        let peak = r.electrodes.iter().cloned().fold(f64::MIN, f64::max);
        assert!(peak > 0.6 * 2.0 * ELECTRODE_PER_N && peak < 2.0 * ELECTRODE_PER_N + 5.0);
        let rms = |v: f64, s: &mut SimBiotac| {
            let pac: Vec<f64> = (0..200)
                .flat_map(|_| s.reading(1.0, v, [0.0, 0.0]).pac)
                .collect();
            (pac.iter().map(|x| x * x).sum::<f64>() / pac.len() as f64).sqrt()
        };
        // The spot moved 5 mm along the layout's x: the pressure-weighted centroid of the
        // electrodes (as graspd computes it) follows, and pdc does not change.
        let mean_over = |moved: [f64; 2], s: &mut SimBiotac| {
            let mut c = [0.0, 0.0];
            for _ in 0..50 {
                let e = s.reading(2.0, 0.0, moved).electrodes;
                let p = graspd_core::tactile::centroid_slip::contact_centroid(&layout, &e, None)
                    .unwrap();
                c = [c[0] + p[0] / 50.0, c[1] + p[1] / 50.0];
            }
            c
        };
        let (c0, c1) = (mean_over([0.0, 0.0], &mut s), mean_over([5.0, 0.0], &mut s));
        assert!(
            c1[0] - c0[0] > 2.0 && (c1[1] - c0[1]).abs() < 0.5,
            "{c0:?} → {c1:?}"
        );
        let still = rms(0.0, &mut s);
        let sliding = rms(0.01, &mut s);
        assert!((still - NOISE_COUNTS).abs() < 0.1, "{still}");
        // std = (k·v + noise) = 21 counts at 1 cm/s.
        assert!(
            (sliding - (PAC_PER_M_S * 0.01 + NOISE_COUNTS)).abs() < 1.0,
            "{sliding}"
        );
    }
}
