//! `graspctl tactile …`: fit a calibration on a folder of labelled recordings, list and delete
//! calibrations (issue 16).
//!
//! A folder of recordings: every `*_bio.csv` under DIR (two levels deep at most; with
//! `--all-csv` every `*.csv` but the arm's files and `labels.csv`, for a sensor whose files are
//! named otherwise — an electrodes-only CSV is told by its columns, `tactile::recording`), with
//! the arm's `*_cw.csv` and `*_cv.csv` beside it when present (frame events). A recording's
//! labels are given by its folder (relative to DIR): a `labels.csv` in DIR (or `--labels FILE`)
//! maps folders to labels, one `folder,material[,event[,slip direction]]` per line
//! (`mat5,plastic/mat5`; a held touch `t,,contact`, a slide north `n,,slip,north`: the event
//! of every frame of the folder's recordings and the direction they slip in);
//! without one the folder's own path is the material (`DIR/foam/…`, `DIR/plastic/eva/…`).

use crate::{CliError, connect_tactile};
use clap::{Args, Subcommand};
use graspd_api::convert;
use graspd_api::json::{CalibrationJson, CalibrationsJson, EventWindowsJson, LabelCountJson};
use graspd_api::request::{CalibrationUpload, RecordingUpload};
use graspd_core::FieldError;
use graspd_core::tactile::{Baseline, ElectrodePolarity, TareConfig};
use graspd_proto::v1 as pb;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Debug, Subcommand)]
pub enum TactileCommand {
    /// Fit a calibration on a folder of labelled recordings and store it on the server.
    Calibrate(CalibrateArgs),
    /// List the server's calibrations.
    Calibrations,
    /// Delete a calibration.
    Delete {
        /// The calibration's name.
        name: String,
    },
}

#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// The folder of recordings.
    dir: PathBuf,
    /// The calibration's name (sessions name it as their detector).
    #[arg(long)]
    name: String,
    /// folder,material[,event[,slip direction]] lines [DIR/labels.csv when present, else the
    /// folder names as materials].
    #[arg(long, value_name = "FILE")]
    labels: Option<PathBuf>,
    /// Replace a calibration of this name.
    #[arg(long)]
    replace: bool,
    /// The recordings are already tared (baseline 0, rising electrodes), like the dexrob set.
    #[arg(long)]
    pretared: bool,
    /// Frames averaged for the baseline at the start of each recording [50].
    #[arg(long, value_name = "N", conflicts_with = "pretared")]
    baseline_frames: Option<usize>,
    /// l of the windows [32].
    #[arg(long)]
    window_length: Option<usize>,
    /// k: every k-th reading [3].
    #[arg(long)]
    stride: Option<usize>,
    /// Leave the arm's files out (no frame events).
    #[arg(long)]
    no_events: bool,
    /// Every *.csv under DIR is a recording (not only *_bio.csv).
    #[arg(long)]
    all_csv: bool,
}

/// A folder's labels: its material, the event of every frame and the slip direction, each
/// optional.
#[derive(Debug, Clone, Default, PartialEq)]
struct FolderLabels {
    material: Option<String>,
    event: Option<String>,
    slip_direction: Option<String>,
}

/// The recordings under `dir`, at most two folders deep, sorted: `*_bio.csv`, or with `all_csv`
/// every `*.csv` but `*_cw.csv`, `*_cv.csv` and `labels.csv`.
fn bio_files(dir: &Path, all_csv: bool) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), 0)];
    while let Some((d, depth)) = stack.pop() {
        for entry in std::fs::read_dir(&d)? {
            let path = entry?.path();
            if path.is_dir() && depth < 2 {
                stack.push((path, depth + 1));
            } else if path.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                n.ends_with("_bio.csv")
                    || (all_csv
                        && n.ends_with(".csv")
                        && !n.ends_with("_cw.csv")
                        && !n.ends_with("_cv.csv")
                        && n != "labels.csv")
            }) {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

fn read(path: &Path) -> Result<String, CliError> {
    std::fs::read_to_string(path).map_err(|source| CliError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// folder → labels from a labels file (`folder,material[,event[,slip direction]]`, any label
/// may be empty).
fn labels(path: &Path) -> Result<BTreeMap<String, FolderLabels>, CliError> {
    let mut map = BTreeMap::new();
    for (i, line) in read(path)?.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let (folder, material, event, direction) = match fields[..] {
            [f, m] => (f, m, "", ""),
            [f, m, e] => (f, m, e, ""),
            [f, m, e, d] => (f, m, e, d),
            _ => {
                return Err(CliError::File {
                    path: path.to_path_buf(),
                    error: FieldError::new(
                        format!("line {}", i + 1),
                        "expected folder,material[,event[,slip direction]]",
                    ),
                });
            }
        };
        let text = |s: &str| (!s.is_empty()).then(|| s.to_string());
        map.insert(
            folder.to_string(),
            FolderLabels {
                material: text(material),
                event: text(event),
                slip_direction: text(direction),
            },
        );
    }
    Ok(map)
}

impl CalibrateArgs {
    /// The upload: every recording of the folder with its material.
    fn upload(&self) -> Result<CalibrationUpload, CliError> {
        let labels_file = self
            .labels
            .clone()
            .or_else(|| Some(self.dir.join("labels.csv")).filter(|p| p.is_file()));
        let labels = labels_file.as_deref().map(labels).transpose()?;
        let files = bio_files(&self.dir, self.all_csv).map_err(|source| CliError::Read {
            path: self.dir.clone(),
            source,
        })?;
        let mut recordings = Vec::new();
        for bio in files {
            let folder = bio
                .parent()
                .and_then(|p| p.strip_prefix(&self.dir).ok())
                .map(|p| p.to_string_lossy().replace('\\', "/"))
                .unwrap_or_default();
            let FolderLabels {
                material,
                event,
                slip_direction,
            } = match &labels {
                Some(l) => l.get(&folder).cloned().unwrap_or_default(),
                None => FolderLabels {
                    material: (!folder.is_empty()).then(|| folder.clone()),
                    ..FolderLabels::default()
                },
            };
            let sibling = |kind: &str| {
                let name = bio.file_name()?.to_str()?.replace("_bio.csv", kind);
                Some(bio.with_file_name(name)).filter(|p| p.is_file())
            };
            let (cw, cv) = match (sibling("_cw.csv"), sibling("_cv.csv")) {
                (Some(cw), Some(cv)) if !self.no_events && event.is_none() => {
                    (Some(read(&cw)?), Some(read(&cv)?))
                }
                _ => (None, None),
            };
            recordings.push(RecordingUpload {
                material,
                bio_csv: read(&bio)?,
                cw_csv: cw,
                cv_csv: cv,
                event,
                slip_direction,
            });
        }
        let tare = if self.pretared {
            TareConfig::pretared()
        } else {
            TareConfig {
                baseline: match (TareConfig::default().baseline, self.baseline_frames) {
                    (_, Some(n)) => Baseline::FirstFrames(n),
                    (b, None) => b,
                },
                electrode_polarity: ElectrodePolarity::Falling,
            }
        };
        Ok(CalibrationUpload {
            name: self.name.clone(),
            replace: self.replace,
            window_length: self.window_length,
            stride: self.stride,
            tare,
            recordings,
        })
    }
}

/// One calibration as text.
fn summary(c: &pb::CalibrationInfo) -> String {
    let counts = |v: &[pb::LabelCount]| {
        if v.is_empty() {
            return "none".to_string();
        }
        let text: Vec<String> = v
            .iter()
            .map(|l| format!("{} {}", l.label, l.windows))
            .collect();
        text.join(", ")
    };
    let events = match c.event_windows.as_slice() {
        [a, b, s] if a + b + s > 0 => {
            format!("non-contact {a}, contact {b}, slip {s}")
        }
        _ => "none".into(),
    };
    let directions = if c.direction_windows.is_empty() {
        String::new()
    } else {
        format!(
            "  slip direction windows: {}\n",
            counts(&c.direction_windows)
        )
    };
    format!(
        "{}: {} electrodes{}, windows of {} every {}, {} recordings fitted in {:.0} ms{}\n  material windows: {}\n  event windows: {events}\n{directions}",
        c.name,
        c.electrodes,
        if c.electrodes_only {
            " (electrodes only)"
        } else {
            ""
        },
        c.window_length,
        c.stride,
        c.recordings,
        c.fit_ms,
        if c.persisted { "" } else { " (in memory only)" },
        counts(&c.material_windows),
    )
}

pub async fn run(
    server: &str,
    token: Option<&str>,
    command: &TactileCommand,
    json: bool,
) -> Result<(), CliError> {
    let mut client = connect_tactile(server, token).await?;
    let infos = match command {
        TactileCommand::Calibrate(args) => {
            let upload = args.upload()?;
            if upload.recordings.is_empty() {
                return Err(CliError::File {
                    path: args.dir.clone(),
                    error: FieldError::new(
                        "DIR",
                        if args.all_csv {
                            "no *.csv recordings under it"
                        } else {
                            "no *_bio.csv recordings under it (--all-csv takes every *.csv)"
                        },
                    ),
                });
            }
            vec![
                client
                    .calibrate(convert::calibrate_request_to_proto(&upload))
                    .await?
                    .into_inner(),
            ]
        }
        TactileCommand::Calibrations => {
            client
                .list_calibrations(pb::ListCalibrationsRequest {})
                .await?
                .into_inner()
                .calibrations
        }
        TactileCommand::Delete { name } => {
            client
                .delete_calibration(pb::DeleteCalibrationRequest { name: name.clone() })
                .await?;
            if !json {
                println!("deleted {name}");
            }
            return Ok(());
        }
    };
    if json {
        let calibrations = infos
            .iter()
            .map(calibration_json)
            .collect::<Result<Vec<_>, _>>()?;
        let text = match command {
            TactileCommand::Calibrations => {
                serde_json::to_string_pretty(&CalibrationsJson { calibrations })?
            }
            _ => serde_json::to_string_pretty(&calibrations[0])?,
        };
        println!("{text}");
    } else {
        for info in &infos {
            print!("{}", summary(info));
        }
    }
    Ok(())
}

/// The answer in the REST API's shape (`CalibrationJson`).
fn calibration_json(c: &pb::CalibrationInfo) -> Result<CalibrationJson, CliError> {
    let label_counts = |v: &[pb::LabelCount]| -> Vec<LabelCountJson> {
        v.iter()
            .map(|l| LabelCountJson {
                label: l.label.clone(),
                windows: l.windows as usize,
            })
            .collect()
    };
    let windows = |i: usize| c.event_windows.get(i).map_or(0, |&n| n as usize);
    Ok(CalibrationJson {
        name: c.name.clone(),
        electrodes: c.electrodes as usize,
        window_length: c.window_length as usize,
        stride: c.stride as usize,
        tare: convert::tare_from_proto(c.tare, "tare").map_err(CliError::Answer)?,
        material_windows: label_counts(&c.material_windows),
        event_windows: (c.event_windows.iter().sum::<u64>() > 0).then(|| EventWindowsJson {
            non_contact: windows(0),
            contact: windows(1),
            slip: windows(2),
        }),
        recordings: c.recordings as usize,
        fit_ms: c.fit_ms,
        persisted: c.persisted,
        electrodes_only: c.electrodes_only,
        direction_windows: label_counts(&c.direction_windows),
    })
}
