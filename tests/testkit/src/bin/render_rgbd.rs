//! Writes the sample RGB-D frame of `examples/rgbd/` (see examples/README.md): a tomato soup can
//! and a mustard bottle rendered on the table by [`graspd_testkit::rgbd`], as `rgb.png`,
//! `depth.png` (16-bit, millimetres) and `request.json` (the REST request part: intrinsics,
//! camera pose, hand).
//!
//! ```text
//! cargo run --release -p graspd-testkit --bin render-rgbd [-- OUT_DIR]
//! ```
//! OUT_DIR defaults to `<workspace>/examples/rgbd`.

use graspd_testkit::Object;
use graspd_testkit::rgbd::{RgbdScene, SceneObject};
use graspd_testkit::workspace_root;
use std::path::PathBuf;
use std::process::ExitCode;

fn run() -> Result<PathBuf, String> {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("examples/rgbd"));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let r = RgbdScene::on_table(vec![
        SceneObject::new(Object::TomatoSoupCan, 0.0, -0.09, [200, 40, 30]),
        SceneObject::new(Object::MustardBottle, 0.03, 0.1, [30, 60, 200]),
    ])
    .render()
    .map_err(|e| e.to_string())?;
    let t = r.camera_to_world.translation.vector;
    let q = r.camera_to_world.rotation;
    let k = r.intrinsics;
    let request = format!(
        "{{\n  \"rgbd\": {{\n    \"intrinsics\": {{\"fx\": {}, \"fy\": {}, \"cx\": {}, \"cy\": {}}},\n    \
         \"camera_to_world\": {{\n      \"position\": [{:.6}, {:.6}, {:.6}],\n      \
         \"orientation\": {{\"x\": {:.9}, \"y\": {:.9}, \"z\": {:.9}, \"w\": {:.9}}}\n    }}\n  }},\n  \
         \"hand_name\": \"parallel_gripper\",\n  \"options\": {{\"seed\": 1}}\n}}\n",
        k.fx, k.fy, k.cx, k.cy, t.x, t.y, t.z, q.i, q.j, q.k, q.w
    );
    let files = [
        ("rgb.png", r.color_png()),
        ("depth.png", r.depth_png()),
        ("request.json", request.into_bytes()),
    ];
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(dir)
}

fn main() -> ExitCode {
    match run() {
        Ok(dir) => {
            println!(
                "wrote rgb.png, depth.png and request.json to {}",
                dir.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("render-rgbd: {e}");
            ExitCode::FAILURE
        }
    }
}
