//! Lets the binaries and tests find libmujoco.so at run time without LD_LIBRARY_PATH: the folder
//! mujoco-rs links from (MUJOCO_DYNAMIC_LINK_DIR, set by the Makefile to .tools/mujoco) goes into
//! the rpath.
fn main() {
    println!("cargo:rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
    }
}
