//! `graspd-sim in-hand-env`: the rotation task served to a trainer (models/in_hand) over a pipe,
//! so that the policy is trained on exactly the scene, state, action and rewards that
//! `graspd-sim` scores it on.
//!
//! The protocol (all numbers little-endian f32):
//! - On start, one line of JSON: `protocol`, `envs` (N), `state_dim`, `action_dim`,
//!   `episode_steps`, `joints`.
//! - `R`: every environment starts an episode; the answer is N states.
//! - `S` and N × action_dim actions: every environment takes one control step; the answer is N
//!   rows of 2·state_dim + 4 numbers: s_{t+1}; the state the next action acts on (s_{t+1}, or
//!   s₀ of the next episode when this one is done: the episodes restart by themselves); r_ext
//!   (Eq 7.12); r_hand (Eq 7.5); the angle to the target (rad); flags (1 done, 2 success,
//!   4 dropped).
//! - `Q` or the end of input: the server exits.

use super::env::{EPISODE_STEPS, InHandEnv, InHandScene};
use super::hand_reward::HandReward;
use crate::SimError;
use std::io::{Read, Write};

/// Numbers after the two states in a step's row.
pub const STEP_EXTRAS: usize = 4;

fn io(e: std::io::Error) -> SimError {
    SimError::Input(format!("in-hand-env pipe: {e}"))
}

fn write_f32(out: &mut impl Write, values: &[f32]) -> Result<(), SimError> {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    out.write_all(&bytes).map_err(io)
}

/// Serves `envs` environments of `scene` (seeded `seed`, `seed + 1`, …) on `input` / `output`
/// until `Q` or the end of `input`.
pub fn serve(
    scene: &InHandScene,
    hand_reward: &HandReward,
    envs: usize,
    seed: u64,
    mut input: impl Read,
    mut output: impl Write,
) -> Result<(), SimError> {
    let mut pool: Vec<InHandEnv> = (0..envs)
        .map(|k| InHandEnv::new(scene, seed.wrapping_add(k as u64)))
        .collect();
    let header = serde_json::json!({
        "protocol": "graspd-in-hand/1",
        "envs": envs,
        "state_dim": scene.state_dim(),
        "action_dim": scene.action_dim(),
        "episode_steps": EPISODE_STEPS,
        "joints": scene.hand_joints.iter().map(|(n, _, _)| n.as_str()).collect::<Vec<_>>(),
    });
    writeln!(output, "{header}").map_err(io)?;
    output.flush().map_err(io)?;
    let nu = scene.action_dim();
    let mut actions = vec![0u8; 4 * nu * envs];
    loop {
        let mut command = [0u8; 1];
        match input.read_exact(&mut command) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(io(e)),
        }
        match command[0] {
            b'R' => {
                for env in &mut pool {
                    let s = env.reset();
                    write_f32(&mut output, &s)?;
                }
            }
            b'S' => {
                input.read_exact(&mut actions).map_err(io)?;
                let a: Vec<f32> = actions
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
                for (env, a) in pool.iter_mut().zip(a.chunks_exact(nu)) {
                    let step = env.step(a);
                    let r_hand = hand_reward.reward(&env.joint_angles());
                    let next = if step.done {
                        env.reset()
                    } else {
                        step.state.clone()
                    };
                    let flags = u8::from(step.done)
                        | u8::from(step.success) << 1
                        | u8::from(step.dropped) << 2;
                    write_f32(&mut output, &step.state)?;
                    write_f32(&mut output, &next)?;
                    write_f32(
                        &mut output,
                        &[
                            step.r_ext as f32,
                            r_hand as f32,
                            step.angle as f32,
                            f32::from(flags),
                        ],
                    )?;
                }
            }
            b'Q' => return Ok(()),
            other => {
                return Err(SimError::Input(format!(
                    "in-hand-env: unknown command byte {other:#04x} (R, S or Q)"
                )));
            }
        }
        output.flush().map_err(io)?;
    }
}
