//! In-hand manipulation (dissertation ch. 7): the object rotation tasks of §7.5 in MuJoCo, their
//! rewards, and the pipe that serves them to the trainer in models/in_hand (docs/in-hand.md).

pub mod env;
pub mod env_server;
pub mod extrinsic_reward;
pub mod hand_reward;
