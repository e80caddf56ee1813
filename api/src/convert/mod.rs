//! proto ↔ domain, one file per message family: [`values`] (vectors, points, poses, planes,
//! enums and the API names of sources), [`perception`] (the perception report), [`tactile`]
//! (sessions, frames and setpoints of the Stabilize stream) and [`calibration`]. Decoding
//! treats a message as untrusted: every error names the offending field by its proto path.

pub mod calibration;
pub mod perception;
pub mod tactile;
pub mod values;

pub use calibration::*;
pub use perception::*;
pub use tactile::*;
pub use values::*;
