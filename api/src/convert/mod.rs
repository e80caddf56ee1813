//! proto ↔ domain, one file per message family: [`values`] (vectors, points, poses, planes,
//! enums and the API names of sources) and [`perception`] (the perception report). Decoding
//! treats a message as untrusted: every error names the offending field by its proto path.

pub mod perception;
pub mod values;

pub use perception::*;
pub use values::*;
