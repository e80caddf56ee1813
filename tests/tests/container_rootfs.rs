//! The container image without a Docker engine: reads the runtime stage of docker/Dockerfile,
//! assembles its file system in a temporary root (COPY from the build context, COPY of the built
//! binaries, the directories its RUN creates), then starts graspd from that root the way the
//! ENTRYPOINT and ENV say, with an otherwise empty environment, and runs the HEALTHCHECK command
//! against it. A runtime file missing from the Dockerfile, a wrong path in ENV, or a shared
//! library the slim base image lacks fails here.

use graspd_e2e::{binary, http};

#[path = "../../service/core/tests/common/onnx_builder.rs"]
mod onnx_builder;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The runtime stage's instructions, continuation lines joined, comments dropped.
fn runtime_stage() -> Vec<String> {
    let text =
        std::fs::read_to_string(repo().join("docker/Dockerfile")).expect("docker/Dockerfile");
    let mut lines = Vec::new();
    let mut current = String::new();
    for raw in text.lines() {
        let line = raw.trim();
        if line.starts_with('#') || (line.is_empty() && current.is_empty()) {
            continue;
        }
        if let Some(head) = line.strip_suffix('\\') {
            current.push_str(head);
            current.push(' ');
        } else {
            current.push_str(line);
            lines.push(std::mem::take(&mut current));
        }
    }
    let start = lines
        .iter()
        .rposition(|l| l.starts_with("FROM ") && l.ends_with(" AS runtime"))
        .expect("a stage `FROM … AS runtime`");
    assert_eq!(
        lines[start], "FROM debian:bookworm-slim AS runtime",
        "the library check below assumes this base"
    );
    lines[start + 1..].to_vec()
}

fn json_array(s: &str) -> Vec<String> {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("not a JSON array: {s}: {e}"))
}

struct Image {
    root: PathBuf,
    env: BTreeMap<String, String>,
    entrypoint: Vec<String>,
    healthcheck: Vec<String>,
    workdir: String,
}

/// In-image path → path under the temporary root.
fn under(root: &Path, p: &str) -> PathBuf {
    root.join(p.trim_start_matches('/'))
}

fn assemble(root: &Path) -> Image {
    let mut image = Image {
        root: root.to_path_buf(),
        env: BTreeMap::new(),
        entrypoint: Vec::new(),
        healthcheck: Vec::new(),
        workdir: "/".into(),
    };
    for line in runtime_stage() {
        let (op, rest) = line.split_once(' ').unwrap_or((&line, ""));
        match op {
            "RUN" => {
                // The directories the image creates (user creation is not replayed).
                for part in rest.split("&&") {
                    if let Some(dirs) = part.trim().strip_prefix("mkdir -p ") {
                        for d in dirs.split_whitespace() {
                            std::fs::create_dir_all(under(root, d)).unwrap();
                        }
                    }
                }
            }
            "COPY" => {
                let words: Vec<&str> = rest.split_whitespace().collect();
                let (from_builder, src, dest) = match words.as_slice() {
                    [from, src, dest] if *from == "--from=builder" => (true, *src, *dest),
                    [src, dest] => (false, *src, *dest),
                    _ => panic!("unexpected COPY: {line}"),
                };
                let source = if from_builder {
                    match src.strip_prefix("/src/target/release/") {
                        // `make test` builds debug binaries; the image's are the release build
                        // of the same sources.
                        Some(name) => binary(name, &format!("{}_BIN", name.to_uppercase())),
                        // What the builder fetched into the checkout (`make test` fetches it
                        // too, e.g. .tools/onnxruntime).
                        None => repo().join(src.strip_prefix("/src/").unwrap_or_else(|| {
                            panic!("the builder's files are under /src: {line}")
                        })),
                    }
                } else {
                    repo().join(src)
                };
                assert!(
                    source.is_file(),
                    "{line}: {} does not exist",
                    source.display()
                );
                let target = under(root, dest);
                std::fs::create_dir_all(target.parent().unwrap()).unwrap();
                std::fs::copy(&source, &target).unwrap();
            }
            "ENV" => {
                let (k, v) = rest.split_once('=').expect("ENV KEY=VALUE");
                image.env.insert(k.to_string(), v.to_string());
            }
            "ENTRYPOINT" => image.entrypoint = json_array(rest),
            "WORKDIR" => {
                image.workdir = rest.to_string();
                std::fs::create_dir_all(under(root, rest)).unwrap();
            }
            "HEALTHCHECK" => {
                let cmd = rest.split_once("CMD ").expect("HEALTHCHECK … CMD [...]").1;
                image.healthcheck = json_array(cmd);
            }
            "USER" | "EXPOSE" => {}
            other => panic!("the rootfs test does not know the instruction {other}: {line}"),
        }
    }
    image
}

/// An absolute in-image path in a value becomes its place under the root.
fn rooted(image: &Image, value: &str) -> String {
    if value.starts_with('/') {
        under(&image.root, value).to_string_lossy().into_owned()
    } else {
        value.to_string()
    }
}

#[test]
fn the_runtime_image_links_only_what_debian_slim_has() {
    // glibc and libgcc are in debian:bookworm-slim; anything else must be installed there.
    let allowed = [
        "linux-vdso.so",
        "libc.so.6",
        "libm.so.6",
        "libgcc_s.so.1",
        "libpthread.so.0",
        "libdl.so.2",
        "librt.so.1",
        "ld-linux-x86-64.so.2",
    ];
    // libstdc++ too, for ONNX Runtime (apt itself depends on it in the slim image).
    let ort = repo().join(".tools/onnxruntime/libonnxruntime.so.1.31.1");
    let with_cxx = [&allowed[..], &["libstdc++.so.6"]].concat();
    for (name, path, allowed) in [
        ("graspd", binary("graspd", "GRASPD_BIN"), &allowed[..]),
        ("graspctl", binary("graspctl", "GRASPCTL_BIN"), &allowed[..]),
        ("libonnxruntime", ort, &with_cxx[..]),
    ] {
        let out = Command::new("ldd").arg(&path).output().expect("ldd");
        let text = String::from_utf8_lossy(&out.stdout);
        for lib in text.lines().filter_map(|l| l.split_whitespace().next()) {
            let file = lib.rsplit('/').next().unwrap();
            assert!(
                allowed.iter().any(|a| file.starts_with(a)),
                "{name} links {file}, which debian:bookworm-slim lacks: install it in docker/Dockerfile's runtime stage\n{text}"
            );
        }
    }
}

#[tokio::test]
async fn graspd_starts_from_the_assembled_image_and_passes_its_healthcheck() {
    let root = std::env::temp_dir().join(format!("graspd-rootfs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let image = assemble(&root);
    assert_eq!(image.entrypoint, ["/usr/local/bin/graspd"]);
    let config = image.env.get("GRASPD_CONFIG").expect("ENV GRASPD_CONFIG");
    assert!(
        Path::new(&rooted(&image, config)).is_file(),
        "{config} is not in the image"
    );

    let mut command = Command::new(rooted(&image, &image.entrypoint[0]));
    command
        .env_clear()
        .current_dir(under(&root, &image.workdir))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in &image.env {
        command.env(k, rooted(&image, v));
    }
    // Ephemeral loopback ports instead of the image's fixed ones (the environment overrides the
    // config file, as in `docker run -e`).
    command
        .env("GRASPD_GRPC_ADDR", "127.0.0.1:0")
        .env("GRASPD_REST_ADDR", "127.0.0.1:0")
        .env("GRASPD_PROBE_ADDR", "127.0.0.1:0");
    // A grasp-type model (the contract's smallest: a 1×1 convolution) proves that the image's
    // ONNX Runtime loads.
    let model = root.join("model.onnx");
    let weights = vec![vec![0.0f32; 3]; 6];
    std::fs::write(
        &model,
        onnx_builder::conv1x1_model(3, &weights, &[0.0; 6], 1, None, None).build(),
    )
    .unwrap();
    command.env("GRASPD_GRASP_TYPE_MODEL", &model);
    let mut child = command.spawn().expect("start graspd from the image root");
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line.starts_with("graspd listening ") {
                let _ = tx.send(line);
            }
        }
    });
    let line = match rx.recv_timeout(Duration::from_secs(30)) {
        Ok(line) => line,
        Err(_) => {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "graspd did not start from the image: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    };
    let field = |key: &str| {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .unwrap_or_else(|| panic!("no {key} in {line}"))
            .to_string()
    };
    let rest = field("rest=");
    let probe = field("probe=");

    let ready = http()
        .get(format!("http://{rest}/readyz"))
        .send()
        .await
        .unwrap();
    assert_eq!(ready.status(), 200);
    let plan = http()
        .post(format!("http://{rest}/v1/plan"))
        .header("content-type", "application/json")
        .body(std::fs::read(repo().join("examples/tomato_soup_can.json")).unwrap())
        .send()
        .await
        .unwrap();
    assert_eq!(plan.status(), 200);

    // The image's HEALTHCHECK, run as Docker runs it: in the container's environment (here with
    // this run's probe port in place of the image's fixed one).
    let health = |command: &mut Command| {
        command
            .env_clear()
            .current_dir(under(&root, &image.workdir))
            .stdin(Stdio::null())
            .stderr(Stdio::null());
        for (k, v) in &image.env {
            command.env(k, rooted(&image, v));
        }
        command
            .env("GRASPD_PROBE_ADDR", &probe)
            .status()
            .expect("run the HEALTHCHECK command")
            .success()
    };
    let check = &image.healthcheck;
    assert_eq!(check[1..], ["--probe"], "{check:?}");
    let mut command = Command::new(rooted(&image, &check[0]));
    assert!(
        health(command.args(&check[1..])),
        "HEALTHCHECK failed: {check:?}"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    // A closed port fails it.
    let mut command = Command::new(rooted(&image, &check[0]));
    assert!(
        !health(command.args(&check[1..])),
        "HEALTHCHECK passes with graspd stopped"
    );
    let _ = std::fs::remove_dir_all(&root);
}
