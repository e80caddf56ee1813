//! Generates the Rust code of `graspd/v1/*.proto` with protox (pure Rust; no system protoc), and
//! writes the file descriptor set that the server's reflection service publishes.

use prost::Message;
use std::path::PathBuf;

const PROTOS: [&str; 7] = [
    "graspd/v1/common.proto",
    "graspd/v1/hand.proto",
    "graspd/v1/ros.proto",
    "graspd/v1/plan.proto",
    "graspd/v1/reach.proto",
    "graspd/v1/grasp_planner.proto",
    "graspd/v1/tactile_stabilizer.proto",
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for p in PROTOS {
        println!("cargo:rerun-if-changed={p}");
    }
    let fds = protox::compile(PROTOS, ["."])?;
    let out = PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out.join("graspd_descriptor.bin"), fds.encode_to_vec())?;
    tonic_prost_build::configure().compile_fds(fds)?;
    Ok(())
}
