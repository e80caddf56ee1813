//! Writes the sample clouds of `examples/` (see examples/README.md).
//!
//! ```text
//! cargo run --release -p graspd-testkit --bin make-clouds [-- OUT_DIR]
//! ```
//! OUT_DIR defaults to `<workspace>/examples`.

use graspd_core::cloud::io::{write_pcd_ascii, write_ply_binary};
use graspd_testkit::{Object, ViewCloud, standard_view, workspace_root};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const N_POINTS: usize = 2000;
const SEED: u64 = 1;

/// Rounds to 0.1 mm and prints without trailing zeros.
fn mm10(v: f64) -> String {
    let r = (v * 1e4).round() / 1e4;
    let r = if r == 0.0 { 0.0 } else { r }; // no "-0"
    format!("{r}")
}

fn xyz(p: &nalgebra::Point3<f64>) -> String {
    format!("[{}, {}, {}]", mm10(p.x), mm10(p.y), mm10(p.z))
}

/// The REST request body of the README's curl example.
fn request_json(v: &ViewCloud) -> String {
    let mut s = String::from("{\n  \"cloud\": {\n    \"points\": [\n");
    for (i, p) in v.cloud.points.iter().enumerate() {
        let sep = if i + 1 < v.cloud.len() { "," } else { "" };
        let _ = writeln!(s, "      {}{sep}", xyz(p));
    }
    let n = v.support_plane.normal;
    let _ = write!(
        s,
        "    ]\n  }},\n  \"hand_name\": \"parallel_gripper\",\n  \"options\": {{\"seed\": 1}},\n  \
         \"hints\": {{\n    \"support_plane\": {{\"normal\": [{}, {}, {}], \"offset\": {}}},\n    \
         \"viewpoint\": {}\n  }}\n}}\n",
        n.x,
        n.y,
        n.z,
        v.support_plane.offset,
        xyz(&v.viewpoint)
    );
    s
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::io::Result<()> {
    let path = dir.join(name);
    std::fs::write(&path, bytes)?;
    println!("wrote {} ({} bytes)", path.display(), bytes.len());
    Ok(())
}

fn run(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let can = standard_view(Object::TomatoSoupCan, N_POINTS, SEED);
    write(
        dir,
        "tomato_soup_can.ply",
        &write_ply_binary(&can.cloud.points, None),
    )?;
    write(dir, "tomato_soup_can.json", request_json(&can).as_bytes())?;
    println!(
        "  tomato soup can: viewpoint {}, object centre {}",
        xyz(&can.viewpoint),
        xyz(&can.object_center)
    );
    let banana = standard_view(Object::Banana, N_POINTS, SEED);
    write(
        dir,
        "banana.pcd",
        &write_pcd_ascii(&banana.cloud.points, None),
    )?;
    println!(
        "  banana: viewpoint {}, object centre {}",
        xyz(&banana.viewpoint),
        xyz(&banana.object_center)
    );
    Ok(())
}

fn main() -> ExitCode {
    let dir = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("examples"));
    match run(&dir) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("make-clouds: {e}");
            ExitCode::FAILURE
        }
    }
}
