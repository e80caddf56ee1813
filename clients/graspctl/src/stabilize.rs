//! `graspctl stabilize`: replay a BioTac recording through the `Stabilize` stream.
//!
//! Frames are sent at the recording's own rate (its timestamps) or, with `--fast`, as fast as
//! the stream takes them. A sender task feeds a bounded channel, so a slow server slows the
//! replay instead of buffering the recording in memory; the main task reads the one setpoint per
//! frame, prints a live line on a terminal (or JSON lines with `--json`), and a summary at the end:
//! frames, events, materials, force and setpoint ranges, and the round-trip time per frame.

use crate::CliError;
use clap::Args;
use graspd_api::convert;
use graspd_api::json::{self, AnalyzeCsvQuery, SetpointJson};
use graspd_core::tactile::{
    ContactEvent, ControlMode, ElectrodePolarity, FrameResult, Material, Recording,
};
use graspd_proto::v1 as pb;
use graspd_proto::v1::stabilize_request::Kind;
use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;
use tonic::codegen::tokio_stream::wrappers::ReceiverStream;

#[derive(Debug, Args)]
pub struct StabilizeArgs {
    /// A `_bio.csv` recording of one finger (`timestamp,tdc,tac,pdc,pac1..pac22,ele1..eleN`, the
    /// layout of the dexrob BioTac recordings).
    #[arg(long, value_name = "FILE")]
    csv: PathBuf,
    /// Send as fast as the stream takes the frames instead of at the recording's rate.
    #[arg(long)]
    fast: bool,
    /// The finger's name in the session.
    #[arg(long, default_value = "finger")]
    finger: String,
    /// The sensor layout: biotac (19 electrodes) or biotac_sp (24).
    #[arg(long, default_value = "biotac")]
    layout: String,
    /// The recording is already tared (baseline 0, rising electrodes), like the dexrob set.
    #[arg(long)]
    pretared: bool,
    /// Frames averaged for the baseline at session start (the recording must start without
    /// contact) [server default 50].
    #[arg(long, value_name = "N")]
    baseline_frames: Option<usize>,
    /// rising or falling [falling, or rising with --pretared].
    #[arg(long, value_name = "POLARITY", value_parser = parse_polarity)]
    electrode_polarity: Option<ElectrodePolarity>,
    /// l, the detector's window length [32].
    #[arg(long)]
    window_length: Option<usize>,
    /// k, every k-th reading enters the window [3].
    #[arg(long)]
    stride: Option<usize>,
    /// f0 of the desired-force law (Eq 6.8).
    #[arg(long)]
    f0: Option<f64>,
    /// δf_m (Eq 6.8).
    #[arg(long)]
    delta_material: Option<f64>,
    /// δf_s (Eq 6.9).
    #[arg(long)]
    delta_slip: Option<f64>,
    #[arg(long)]
    f_min: Option<f64>,
    #[arg(long)]
    f_max: Option<f64>,
    #[arg(long)]
    kp: Option<f64>,
    #[arg(long)]
    ki: Option<f64>,
    #[arg(long)]
    kd: Option<f64>,
    /// α of Eq 6.6.
    #[arg(long)]
    alpha: Option<f64>,
    /// Newtons per raw unit of Eq 6.7 (unset: forces in raw units).
    #[arg(long)]
    calibration_gain: Option<f64>,
    /// Detect with this calibration of the server (`graspctl tactile calibrate`); the window,
    /// the stride and the taring must be those it was fitted with.
    #[arg(long, value_name = "NAME")]
    calibration: Option<String>,
    /// Latched slip, a deviation from Eq 6.9: each slip episode raises f_d by δf_s until the
    /// finger loses contact.
    #[arg(long)]
    latch_slip: bool,
    /// Slip from the contact centroid's motion: a finger in contact whose electrode centroid
    /// moves faster than this (mm/s) slips.
    #[arg(long, value_name = "MM_S")]
    centroid_slip_mm_s: Option<f64>,
    /// The sensor gives only its electrodes: pdc, pac, tdc and tac are not read; slip comes
    /// from the contact centroid's motion.
    #[arg(long)]
    electrodes_only: bool,
    /// Print no live line, only the summary.
    #[arg(long)]
    quiet: bool,
}

fn parse_polarity(s: &str) -> Result<ElectrodePolarity, String> {
    serde_json::from_value(serde_json::Value::String(s.to_string()))
        .map_err(|_| format!("'{s}': expected rising or falling"))
}

impl StabilizeArgs {
    /// The session, built exactly as `POST /v1/tactile/analyze` builds it from its CSV query, so
    /// a replay and an analyze call with the same options give the same results.
    fn session(&self) -> pb::TactileSession {
        let query = AnalyzeCsvQuery {
            finger: Some(self.finger.clone()),
            layout: Some(self.layout.clone()),
            pretared: self.pretared,
            baseline_frames: self.baseline_frames,
            electrode_polarity: self.electrode_polarity,
            window_length: self.window_length,
            stride: self.stride,
            f0: self.f0,
            delta_material: self.delta_material,
            delta_slip: self.delta_slip,
            f_min: self.f_min,
            f_max: self.f_max,
            kp: self.kp,
            ki: self.ki,
            kd: self.kd,
            alpha: self.alpha,
            calibration_gain: self.calibration_gain,
            calibration: self.calibration.clone(),
            latch_slip: self.latch_slip.then_some(true),
            centroid_slip_mm_s: self.centroid_slip_mm_s,
            electrodes_only: self.electrodes_only,
        };
        convert::tactile_session_to_proto(&json::tactile_session_from_json(query.session()))
    }
}

/// What the summary counts over the replay.
#[derive(Debug, Default)]
pub struct Summary {
    frames: usize,
    events: [usize; 3],
    materials: [usize; 5],
    force_mode_frames: usize,
    mode_switches: usize,
    max_force: f64,
    desired: Option<(f64, f64)>,
    setpoints: Option<(f64, f64)>,
    round_trips_us: Vec<f64>,
    unit: &'static str,
}

impl Summary {
    fn add(&mut self, r: &FrameResult, previous_mode: &mut Option<ControlMode>) {
        self.frames += 1;
        let Some(f) = r.fingers.first() else { return };
        self.events[match f.event {
            ContactEvent::NonContact => 0,
            ContactEvent::Contact => 1,
            ContactEvent::Slip => 2,
        }] += 1;
        self.materials[match f.material {
            Material::Unknown => 0,
            Material::Paper => 1,
            Material::Foam => 2,
            Material::Plastic => 3,
            Material::Metal => 4,
        }] += 1;
        if f.mode == ControlMode::Force {
            self.force_mode_frames += 1;
            let fd = f.desired_force;
            self.desired = Some(match self.desired {
                Some((lo, hi)) => (lo.min(fd), hi.max(fd)),
                None => (fd, fd),
            });
        }
        if previous_mode.is_some_and(|m| m != f.mode) {
            self.mode_switches += 1;
        }
        *previous_mode = Some(f.mode);
        self.max_force = self.max_force.max(f.force);
        if let Some(s) = f.setpoint {
            self.setpoints = Some(match self.setpoints {
                Some((lo, hi)) => (lo.min(s), hi.max(s)),
                None => (s, s),
            });
        }
        self.unit = match f.force_unit {
            graspd_core::tactile::ForceUnit::Raw => "raw",
            graspd_core::tactile::ForceUnit::Newton => "N",
        };
    }

    fn render(&self, path: &std::path::Path, elapsed: Duration, recorded_s: f64) -> String {
        let mut s = String::new();
        let pct = |n: usize| 100.0 * n as f64 / self.frames.max(1) as f64;
        let _ = writeln!(
            s,
            "{}: {} frames ({:.2} s recorded) in {:.2} s, {:.0} frames/s",
            path.display(),
            self.frames,
            recorded_s,
            elapsed.as_secs_f64(),
            self.frames as f64 / elapsed.as_secs_f64().max(1e-9)
        );
        let _ = writeln!(
            s,
            "  events     non-contact {:.1} %, contact {:.1} %, slip {:.1} %",
            pct(self.events[0]),
            pct(self.events[1]),
            pct(self.events[2])
        );
        let names = ["unknown", "paper", "foam", "plastic", "metal"];
        let materials: Vec<String> = names
            .iter()
            .zip(self.materials)
            .filter(|(_, n)| *n > 0)
            .map(|(name, n)| format!("{name} {:.1} %", pct(n)))
            .collect();
        let _ = writeln!(s, "  material   {}", materials.join(", "));
        let _ = writeln!(
            s,
            "  control    force mode {:.1} % of frames, {} mode switches",
            pct(self.force_mode_frames),
            self.mode_switches
        );
        let range = |r: Option<(f64, f64)>| match r {
            Some((lo, hi)) => format!("{lo:.3} … {hi:.3} {}", self.unit),
            None => "none (position mode throughout)".into(),
        };
        let _ = writeln!(
            s,
            "  force      max estimated {:.3} {}; desired {}",
            self.max_force,
            self.unit,
            range(self.desired)
        );
        let _ = writeln!(s, "  setpoint   {}", range(self.setpoints));
        if let Some((_, hi)) = self.desired
            && self.unit == "raw"
            && self.max_force > 10.0 * hi
        {
            let _ = writeln!(
                s,
                "  note       the forces are raw sensor units, far above f_d: give --calibration-gain (N per raw unit) or f0, f_min, f_max in raw units"
            );
        }
        let mut rt = self.round_trips_us.clone();
        rt.sort_by(f64::total_cmp);
        if !rt.is_empty() {
            let q = |p: f64| rt[((rt.len() - 1) as f64 * p).round() as usize];
            let _ = writeln!(
                s,
                "  round trip p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs (send to setpoint; with --fast it includes queueing)",
                q(0.5),
                q(0.99),
                rt[rt.len() - 1]
            );
        }
        s
    }
}

fn live_line(i: usize, total: usize, r: &FrameResult) -> String {
    let mut line = format!("\r{:>6}/{total} t={:>8.3}", i + 1, r.timestamp);
    for f in &r.fingers {
        let _ = write!(
            line,
            "  {} {:<11} {:<8} f={:>8.3} fd={:>8.3} {}",
            f.finger,
            f.event.name(),
            f.material.name(),
            f.force,
            f.desired_force,
            match f.setpoint {
                Some(s) => format!("u={s:>8.3}"),
                None => "position  ".into(),
            }
        );
    }
    line
}

pub async fn run(
    server: &str,
    token: Option<&str>,
    args: &StabilizeArgs,
    as_json: bool,
) -> Result<(), CliError> {
    let text = String::from_utf8_lossy(&crate::read(&args.csv)?).into_owned();
    let frames = Recording::from_csv(&text, None, None)
        .map_err(|error| CliError::File {
            path: args.csv.clone(),
            error,
        })?
        .frames();
    let total = frames.len();
    let recorded_s = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) => b.timestamp - a.timestamp,
        _ => 0.0,
    };
    let mut client = crate::connect_tactile(server, token).await?;

    // Bounded: at most 64 frames wait in this client when the server is slower than the replay.
    let (tx, rx) = mpsc::channel(64);
    let (sent_tx, mut sent_rx) = mpsc::unbounded_channel::<Instant>();
    tx.send(pb::StabilizeRequest {
        kind: Some(Kind::Session(args.session())),
    })
    .await
    .map_err(|_| CliError::Answer(graspd_core::FieldError::new("stream", "closed")))?;
    let fast = args.fast;
    let started = Instant::now();
    let sender = tokio::spawn(async move {
        let t0 = frames.first().map_or(0.0, |f| f.timestamp);
        for f in &frames {
            if !fast {
                let due = started + Duration::from_secs_f64((f.timestamp - t0).max(0.0));
                tokio::time::sleep_until(due.into()).await;
            }
            let message = pb::StabilizeRequest {
                kind: Some(Kind::Frame(convert::tactile_frame_to_proto(f))),
            };
            let _ = sent_tx.send(Instant::now());
            if tx.send(message).await.is_err() {
                break; // the stream ended (the server's error is read by the receiver)
            }
        }
    });

    let mut stream = client
        .stabilize(ReceiverStream::new(rx))
        .await?
        .into_inner();
    let live = !as_json && !args.quiet && std::io::stdout().is_terminal();
    let mut summary = Summary::default();
    let mut previous_mode = None;
    let mut last_print = Instant::now() - Duration::from_secs(1);
    let mut stdout = std::io::stdout().lock();
    let result = loop {
        match stream.message().await {
            Ok(Some(m)) => {
                let index = m.frame_index;
                let result = convert::setpoint_from_proto(m).map_err(CliError::Answer)?;
                if let Some(sent) = sent_rx.recv().await {
                    summary
                        .round_trips_us
                        .push(sent.elapsed().as_secs_f64() * 1e6);
                }
                summary.add(&result, &mut previous_mode);
                if as_json {
                    let line = serde_json::to_string(&SetpointJson {
                        frame_index: index,
                        result,
                    })?;
                    let _ = writeln!(stdout, "{line}");
                } else if live && last_print.elapsed() >= Duration::from_millis(50) {
                    let _ = write!(stdout, "{}", live_line(index as usize, total, &result));
                    let _ = stdout.flush();
                    last_print = Instant::now();
                }
            }
            Ok(None) => break Ok(()),
            Err(status) => break Err(CliError::Status(status)),
        }
    };
    sender.abort();
    if live {
        let _ = writeln!(stdout);
    }
    result?;
    let report = summary.render(&args.csv, started.elapsed(), recorded_s);
    if as_json {
        eprint!("{report}");
    } else {
        let _ = write!(stdout, "{report}");
    }
    if summary.frames != total {
        return Err(CliError::Answer(graspd_core::FieldError::new(
            "stream",
            format!("{} setpoints for {total} frames", summary.frames),
        )));
    }
    Ok(())
}
