//! Configuration: flags > environment > TOML file (`--config`) > built-in defaults.
//!
//! clap resolves flag over environment; whatever neither gives falls back to the file and then
//! to the defaults, so every flag is an `Option` here.

use crate::facade::{HandSetup, Limits, QUEUED_PLANS_PER_PLANNER};
use crate::ops::Tokens;
use crate::tls::TlsFiles;
use clap::{Parser, ValueEnum};
use graspd_core::cloud::MIN_POINTS;
use graspd_core::planning::MAX_ITERATIONS;
use serde::{Deserialize, Serialize};
use std::net::SocketAddr;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Clone, Parser)]
#[command(
    name = "graspd",
    version,
    about = "graspd: grasp planning with pregrasping opposition, over gRPC and REST"
)]
pub struct Cli {
    /// TOML configuration file; flags and environment variables override its values.
    #[arg(long, env = "GRASPD_CONFIG", value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// gRPC listen address [default: 0.0.0.0:50051].
    #[arg(long, env = "GRASPD_GRPC_ADDR", value_name = "ADDR")]
    pub grpc_addr: Option<SocketAddr>,
    /// REST listen address [default: 0.0.0.0:8080].
    #[arg(long, env = "GRASPD_REST_ADDR", value_name = "ADDR")]
    pub rest_addr: Option<SocketAddr>,
    /// A plain-HTTP port answering only GET /healthz and /readyz (no TLS, no token): probes
    /// that cannot speak the TLS of the other ports, e.g. with mutual TLS [default: none].
    #[arg(long, env = "GRASPD_PROBE_ADDR", value_name = "ADDR")]
    pub probe_addr: Option<SocketAddr>,
    /// Instead of serving: ask the server this configuration describes whether it is ready
    /// (its probe port, else its REST port, over TLS when configured, the certificate not
    /// verified: a container HEALTHCHECK). Exit 0 when /readyz answers 200.
    #[arg(long)]
    pub probe: bool,
    /// Largest gRPC message / REST body, bytes; accepts KiB/MiB/GiB suffixes [default: 32MiB].
    #[arg(long, env = "GRASPD_MAX_MESSAGE_BYTES", value_name = "BYTES", value_parser = parse_bytes)]
    pub max_message_bytes: Option<usize>,
    /// Largest cloud, points [default: 500000].
    #[arg(long, env = "GRASPD_MAX_POINTS", value_name = "N")]
    pub max_points: Option<usize>,
    /// Plans computed at once; further requests wait [default: number of CPUs].
    #[arg(long, env = "GRASPD_MAX_CONCURRENT_PLANS", value_name = "N")]
    pub max_concurrent_plans: Option<usize>,
    /// Plan requests waiting for a planner; one more is shed with RESOURCE_EXHAUSTED / 503 and
    /// a retry hint [default: 4 × max_concurrent_plans].
    #[arg(long, env = "GRASPD_MAX_QUEUED_PLANS", value_name = "N")]
    pub max_queued_plans: Option<usize>,
    /// On SIGTERM, keep serving this long with /readyz at 503 and gRPC health NOT_SERVING
    /// before the listeners close, so that a load balancer stops sending traffic first
    /// [default: 0].
    #[arg(long, env = "GRASPD_DRAIN_DELAY_MS", value_name = "MS")]
    pub drain_delay_ms: Option<u64>,
    /// A bearer token that gRPC and REST requests must carry (`authorization: Bearer TOKEN`);
    /// repeatable (environment: comma-separated). Replaces the config file's `auth_tokens`.
    /// Without any token, authentication is off. Probes, /metrics and /openapi.json stay open.
    #[arg(
        long = "auth-token",
        env = "GRASPD_AUTH_TOKENS",
        value_name = "TOKEN",
        value_delimiter = ',',
        hide_env_values = true
    )]
    pub auth_tokens: Vec<String>,
    /// A file of bearer tokens, one per line (`#` comments), added to the others.
    #[arg(long, env = "GRASPD_AUTH_TOKENS_FILE", value_name = "FILE")]
    pub auth_tokens_file: Option<PathBuf>,
    /// Tactile sessions open at once (streams and analyze calls); more are refused [default: 64].
    #[arg(long, env = "GRASPD_MAX_TACTILE_SESSIONS", value_name = "N")]
    pub max_tactile_sessions: Option<usize>,
    /// Largest RGB-D frame, width × height pixels [default: 16777216 (4096²)].
    #[arg(long, env = "GRASPD_MAX_IMAGE_PIXELS", value_name = "N")]
    pub max_image_pixels: Option<usize>,
    /// Most further RGB-D views (`extra_views`) fused into one plan request [default: 8].
    #[arg(long, env = "GRASPD_MAX_VIEWS", value_name = "N")]
    pub max_views: Option<usize>,
    /// Most stage-1 iterations a plan request may ask for (`options.max_iterations`), what one
    /// plan may cost in CPU [default: 100000; at most 10000000].
    #[arg(long, env = "GRASPD_MAX_ITERATIONS", value_name = "N")]
    pub max_iterations: Option<usize>,
    /// The grasp-type network (ONNX, docs/model-contract.md) for RGB-D input [default: the copy
    /// of models/grasp_type/grasp_type.onnx built into graspd; if it cannot be loaded (no ONNX
    /// Runtime) graspd warns and the geometric rule decides types]. `none`: no model. A given
    /// file that does not load or breaks the contract stops the start.
    #[arg(long, env = "GRASPD_GRASP_TYPE_MODEL", value_name = "FILE")]
    pub grasp_type_model: Option<PathBuf>,
    /// The tactile contact/slip/material detector (ONNX, models/tactile/MODEL_CARD.md)
    /// [default: the copy of models/tactile/tactile_detector.onnx built into graspd; if it cannot
    /// be loaded (no ONNX Runtime) graspd warns and uses the model-free detector]. `none`: no
    /// model. A given file that does not load or breaks the contract stops the start.
    #[arg(long, env = "GRASPD_TACTILE_MODEL", value_name = "FILE")]
    pub tactile_model: Option<PathBuf>,
    /// The recogniser that finds `hints.object` among the objects in view (ONNX,
    /// models/recogniser/MODEL_CARD.md) [default: the copy of models/recogniser/recogniser.onnx
    /// built into graspd; if it cannot be loaded (no ONNX Runtime) graspd warns and refuses
    /// `hints.object`]. `none`: no model. A given file that does not load or breaks the contract
    /// stops the start.
    #[arg(long, env = "GRASPD_RECOGNISER_MODEL", value_name = "FILE")]
    pub recogniser_model: Option<PathBuf>,
    /// The learned parallel-jaw grasp quality of `options.mode = learned_quality` (ONNX,
    /// models/grasp_quality/MODEL_CARD.md) [default: the copy of
    /// models/grasp_quality/grasp_quality.onnx built into graspd; if it cannot be loaded (no ONNX
    /// Runtime) graspd warns and refuses that mode]. `none`: no model. A given file that does
    /// not load or breaks the contract stops the start.
    #[arg(long, env = "GRASPD_GRASP_QUALITY_MODEL", value_name = "FILE")]
    pub grasp_quality_model: Option<PathBuf>,
    /// libonnxruntime.so (1.31) to load the model with [default: $ORT_DYLIB_PATH].
    #[arg(long, env = "GRASPD_ONNXRUNTIME", value_name = "FILE")]
    pub onnxruntime: Option<PathBuf>,
    /// Threads of one model inference [default: 1].
    #[arg(long, env = "GRASPD_MODEL_THREADS", value_name = "N")]
    pub model_threads: Option<usize>,
    /// Log filter in tracing's EnvFilter syntax, e.g. `info` or `graspd=debug` [default: info].
    #[arg(long, env = "GRASPD_LOG", value_name = "FILTER")]
    pub log: Option<String>,
    /// Log format [default: pretty].
    #[arg(long, env = "GRASPD_LOG_FORMAT", value_enum, value_name = "FORMAT")]
    pub log_format: Option<LogFormat>,
    /// Directory of registered hands: RegisterHand stores hands here and they are loaded again
    /// at start [default: none: registered hands live in memory until the server stops].
    #[arg(long, env = "GRASPD_HANDS_DIR", value_name = "DIR")]
    pub hands_dir: Option<PathBuf>,
    /// Directory of tactile calibrations: Calibrate stores them here and they are loaded again
    /// at start [default: none: calibrations live in memory until the server stops].
    #[arg(long, env = "GRASPD_CALIBRATIONS_DIR", value_name = "DIR")]
    pub calibrations_dir: Option<PathBuf>,
    /// A hand to read at start from its MJCF (.xml) or URDF (.urdf) file, as NAME=PATH;
    /// repeatable (environment: comma-separated). Replaces the config file's `import_hands`.
    #[arg(long = "import-hand", env = "GRASPD_IMPORT_HANDS", value_name = "NAME=PATH", value_delimiter = ',', value_parser = parse_import)]
    pub import_hands: Vec<(String, PathBuf)>,
    /// TLS certificate chain (PEM, server certificate first) for both ports; needs --tls-key
    /// [default: none: plain HTTP/2 and HTTP].
    #[arg(long, env = "GRASPD_TLS_CERT", value_name = "FILE")]
    pub tls_cert: Option<PathBuf>,
    /// The private key (PEM: PKCS#8, PKCS#1 or SEC1) of --tls-cert.
    #[arg(long, env = "GRASPD_TLS_KEY", value_name = "FILE")]
    pub tls_key: Option<PathBuf>,
    /// CA certificates (PEM): with TLS on, clients of both ports must present a certificate
    /// signed by one of them (mutual TLS); others are refused at the handshake.
    #[arg(long, env = "GRASPD_TLS_CLIENT_CA", value_name = "FILE")]
    pub tls_client_ca: Option<PathBuf>,
    /// Print the effective configuration as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LogFormat {
    /// Human-readable lines.
    #[default]
    Pretty,
    /// One JSON object per line.
    Json,
}

/// The config file: the same settings as the flags, all optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileConfig {
    pub grpc_addr: Option<SocketAddr>,
    pub rest_addr: Option<SocketAddr>,
    pub probe_addr: Option<SocketAddr>,
    pub max_message_bytes: Option<usize>,
    pub max_points: Option<usize>,
    pub max_concurrent_plans: Option<usize>,
    pub max_queued_plans: Option<usize>,
    pub drain_delay_ms: Option<u64>,
    pub max_tactile_sessions: Option<usize>,
    pub max_image_pixels: Option<usize>,
    pub max_views: Option<usize>,
    pub max_iterations: Option<usize>,
    /// Bearer tokens, as `--auth-token`.
    #[serde(default)]
    pub auth_tokens: Vec<String>,
    pub auth_tokens_file: Option<PathBuf>,
    pub grasp_type_model: Option<PathBuf>,
    pub tactile_model: Option<PathBuf>,
    pub recogniser_model: Option<PathBuf>,
    pub grasp_quality_model: Option<PathBuf>,
    pub onnxruntime: Option<PathBuf>,
    pub model_threads: Option<usize>,
    pub log: Option<String>,
    pub log_format: Option<LogFormat>,
    pub hands_dir: Option<PathBuf>,
    pub calibrations_dir: Option<PathBuf>,
    /// `["NAME=PATH", …]`, as `--import-hand`.
    #[serde(default)]
    pub import_hands: Vec<String>,
    pub tls_cert: Option<PathBuf>,
    pub tls_key: Option<PathBuf>,
    pub tls_client_ca: Option<PathBuf>,
}

/// The effective configuration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    pub grpc_addr: SocketAddr,
    pub rest_addr: SocketAddr,
    /// The plain-HTTP probe port, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub probe_addr: Option<SocketAddr>,
    pub max_message_bytes: usize,
    pub max_points: usize,
    pub max_concurrent_plans: usize,
    pub max_queued_plans: usize,
    pub drain_delay_ms: u64,
    pub max_tactile_sessions: usize,
    pub max_image_pixels: usize,
    pub max_views: usize,
    pub max_iterations: usize,
    /// Never printed: `--print-config` shows their count in a comment.
    #[serde(skip)]
    pub auth_tokens: Tokens,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auth_tokens_file: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grasp_type_model: Option<PathBuf>,
    /// `None`: the built-in copy; `Some("none")`: no model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tactile_model: Option<PathBuf>,
    /// `None`: the built-in copy; `Some("none")`: no model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recogniser_model: Option<PathBuf>,
    /// `None`: the built-in copy; `Some("none")`: no model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grasp_quality_model: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub onnxruntime: Option<PathBuf>,
    pub model_threads: usize,
    pub log: String,
    pub log_format: LogFormat,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hands_dir: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibrations_dir: Option<PathBuf>,
    /// `NAME=PATH` entries.
    pub import_hands: Vec<String>,
    /// PEM files of TLS (paths only: the key itself is read at start and never printed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tls_cert: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tls_key: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tls_client_ca: Option<PathBuf>,
}

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("cannot read config file {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("config file {path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{field}: {message}")]
    Invalid {
        field: &'static str,
        message: String,
    },
}

impl Settings {
    /// Resolves flag > environment (both in `cli`) > file > default, and checks the values.
    pub fn resolve(cli: &Cli) -> Result<Self, ConfigError> {
        let file = match &cli.config {
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
                    path: path.clone(),
                    source,
                })?;
                toml::from_str::<FileConfig>(&text).map_err(|e| ConfigError::Parse {
                    path: path.clone(),
                    message: e.to_string(),
                })?
            }
            None => FileConfig::default(),
        };
        let d = Limits::default();
        let max_concurrent_plans = cli
            .max_concurrent_plans
            .or(file.max_concurrent_plans)
            .unwrap_or(d.max_concurrent_plans);
        let invalid_tokens = |message| ConfigError::Invalid {
            field: "auth_tokens",
            message,
        };
        let mut auth_tokens = if cli.auth_tokens.is_empty() {
            Tokens::new(&file.auth_tokens, "auth_tokens").map_err(invalid_tokens)?
        } else {
            Tokens::new(&cli.auth_tokens, "--auth-token / GRASPD_AUTH_TOKENS")
                .map_err(invalid_tokens)?
        };
        let auth_tokens_file = cli.auth_tokens_file.clone().or(file.auth_tokens_file);
        if let Some(path) = &auth_tokens_file {
            let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
                path: path.clone(),
                source,
            })?;
            let from_file =
                Tokens::parse_file(&text, &path.display().to_string()).map_err(invalid_tokens)?;
            if from_file.is_empty() {
                return Err(invalid_tokens(format!(
                    "{} holds no token (one per line)",
                    path.display()
                )));
            }
            auth_tokens = auth_tokens.merge(from_file);
        }
        let settings = Settings {
            grpc_addr: cli
                .grpc_addr
                .or(file.grpc_addr)
                .unwrap_or(([0, 0, 0, 0], 50051).into()),
            rest_addr: cli
                .rest_addr
                .or(file.rest_addr)
                .unwrap_or(([0, 0, 0, 0], 8080).into()),
            probe_addr: cli.probe_addr.or(file.probe_addr),
            max_message_bytes: cli
                .max_message_bytes
                .or(file.max_message_bytes)
                .unwrap_or(d.max_message_bytes),
            max_points: cli.max_points.or(file.max_points).unwrap_or(d.max_points),
            max_concurrent_plans,
            max_queued_plans: cli
                .max_queued_plans
                .or(file.max_queued_plans)
                .unwrap_or(QUEUED_PLANS_PER_PLANNER.saturating_mul(max_concurrent_plans)),
            drain_delay_ms: cli.drain_delay_ms.or(file.drain_delay_ms).unwrap_or(0),
            max_tactile_sessions: cli
                .max_tactile_sessions
                .or(file.max_tactile_sessions)
                .unwrap_or(d.max_tactile_sessions),
            max_image_pixels: cli
                .max_image_pixels
                .or(file.max_image_pixels)
                .unwrap_or(d.max_image_pixels),
            max_views: cli.max_views.or(file.max_views).unwrap_or(d.max_views),
            max_iterations: cli
                .max_iterations
                .or(file.max_iterations)
                .unwrap_or(d.max_iterations),
            auth_tokens,
            auth_tokens_file,
            grasp_type_model: cli.grasp_type_model.clone().or(file.grasp_type_model),
            tactile_model: cli.tactile_model.clone().or(file.tactile_model),
            recogniser_model: cli.recogniser_model.clone().or(file.recogniser_model),
            grasp_quality_model: cli.grasp_quality_model.clone().or(file.grasp_quality_model),
            onnxruntime: cli.onnxruntime.clone().or(file.onnxruntime),
            model_threads: cli.model_threads.or(file.model_threads).unwrap_or(1),
            log: cli
                .log
                .clone()
                .or(file.log)
                .unwrap_or_else(|| "info".into()),
            log_format: cli.log_format.or(file.log_format).unwrap_or_default(),
            hands_dir: cli.hands_dir.clone().or(file.hands_dir),
            calibrations_dir: cli.calibrations_dir.clone().or(file.calibrations_dir),
            import_hands: if cli.import_hands.is_empty() {
                for entry in &file.import_hands {
                    parse_import(entry).map_err(|message| ConfigError::Invalid {
                        field: "import_hands",
                        message,
                    })?;
                }
                file.import_hands
            } else {
                cli.import_hands
                    .iter()
                    .map(|(n, p)| format!("{n}={}", p.display()))
                    .collect()
            },
            tls_cert: cli.tls_cert.clone().or(file.tls_cert),
            tls_key: cli.tls_key.clone().or(file.tls_key),
            tls_client_ca: cli.tls_client_ca.clone().or(file.tls_client_ca),
        };
        settings.check()?;
        Ok(settings)
    }

    fn check(&self) -> Result<(), ConfigError> {
        if self.max_message_bytes < 1024 {
            return Err(ConfigError::Invalid {
                field: "max_message_bytes",
                message: format!("must be at least 1024, got {}", self.max_message_bytes),
            });
        }
        if self.max_points < MIN_POINTS {
            return Err(ConfigError::Invalid {
                field: "max_points",
                message: format!("must be at least {MIN_POINTS}, got {}", self.max_points),
            });
        }
        if self.max_concurrent_plans == 0 {
            return Err(ConfigError::Invalid {
                field: "max_concurrent_plans",
                message: "must be at least 1".into(),
            });
        }
        if self.max_image_pixels < 64 * 48 {
            return Err(ConfigError::Invalid {
                field: "max_image_pixels",
                message: format!(
                    "must be at least 3072 (64×48), got {}",
                    self.max_image_pixels
                ),
            });
        }
        if self.max_views > 64 {
            return Err(ConfigError::Invalid {
                field: "max_views",
                message: format!("must be at most 64, got {}", self.max_views),
            });
        }
        if self.max_iterations == 0 || self.max_iterations > MAX_ITERATIONS {
            return Err(ConfigError::Invalid {
                field: "max_iterations",
                message: format!(
                    "must be within 1..={MAX_ITERATIONS}, got {}",
                    self.max_iterations
                ),
            });
        }
        if self.model_threads == 0 || self.model_threads > 64 {
            return Err(ConfigError::Invalid {
                field: "model_threads",
                message: format!("must be within 1..=64, got {}", self.model_threads),
            });
        }
        if self.drain_delay_ms > 600_000 {
            return Err(ConfigError::Invalid {
                field: "drain_delay_ms",
                message: format!(
                    "must be at most 600000 (10 min), got {}",
                    self.drain_delay_ms
                ),
            });
        }
        if self.max_tactile_sessions == 0 {
            return Err(ConfigError::Invalid {
                field: "max_tactile_sessions",
                message: "must be at least 1".into(),
            });
        }
        match (&self.tls_cert, &self.tls_key) {
            (Some(cert), None) => {
                return Err(ConfigError::Invalid {
                    field: "tls_key",
                    message: format!(
                        "--tls-cert {} is set but --tls-key is not: give both (or neither)",
                        cert.display()
                    ),
                });
            }
            (None, Some(key)) => {
                return Err(ConfigError::Invalid {
                    field: "tls_cert",
                    message: format!(
                        "--tls-key {} is set but --tls-cert is not: give both (or neither)",
                        key.display()
                    ),
                });
            }
            _ => {}
        }
        if let (Some(ca), None) = (&self.tls_client_ca, &self.tls_cert) {
            return Err(ConfigError::Invalid {
                field: "tls_client_ca",
                message: format!(
                    "--tls-client-ca {} needs TLS: give --tls-cert and --tls-key too",
                    ca.display()
                ),
            });
        }
        Ok(())
    }

    /// The TLS files, when TLS is on (both certificate and key given; [`Settings::resolve`]
    /// refuses one without the other).
    pub fn tls_files(&self) -> Option<TlsFiles> {
        Some(TlsFiles {
            cert: self.tls_cert.clone()?,
            key: self.tls_key.clone()?,
            client_ca: self.tls_client_ca.clone(),
        })
    }

    /// The hands to load at start.
    pub fn hand_setup(&self) -> HandSetup {
        HandSetup {
            hands_dir: self.hands_dir.clone(),
            imports: self
                .import_hands
                .iter()
                .filter_map(|e| parse_import(e).ok())
                .collect(),
        }
    }

    pub fn limits(&self) -> Limits {
        Limits {
            max_message_bytes: self.max_message_bytes,
            max_points: self.max_points,
            max_concurrent_plans: self.max_concurrent_plans,
            max_queued_plans: self.max_queued_plans,
            max_tactile_sessions: self.max_tactile_sessions,
            max_image_pixels: self.max_image_pixels,
            max_views: self.max_views,
            max_iterations: self.max_iterations,
        }
    }
}

/// Parses `NAME=PATH` of `--import-hand`.
pub fn parse_import(s: &str) -> Result<(String, PathBuf), String> {
    let (name, path) = s.split_once('=').ok_or_else(|| {
        format!("'{s}' is not NAME=PATH (e.g. allegro=hands/allegro/right_hand.xml)")
    })?;
    let (name, path) = (name.trim(), path.trim());
    if name.is_empty() || path.is_empty() {
        return Err(format!("'{s}' is not NAME=PATH: empty name or path"));
    }
    Ok((name.to_string(), PathBuf::from(path)))
}

/// Parses a byte count: `1048576`, `512KiB`, `32MiB`, `1GiB` (also `K`, `M`, `G`, binary).
pub fn parse_bytes(s: &str) -> Result<usize, String> {
    let s = s.trim();
    let split = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    let (digits, unit) = s.split_at(split);
    let n: usize = digits
        .parse()
        .map_err(|_| format!("'{s}' is not a byte count (e.g. 1048576 or 32MiB)"))?;
    let scale: usize = match unit.trim() {
        "" | "B" => 1,
        "K" | "KiB" | "k" => 1 << 10,
        "M" | "MiB" => 1 << 20,
        "G" | "GiB" => 1 << 30,
        other => return Err(format!("unknown unit '{other}' (use KiB, MiB or GiB)")),
    };
    n.checked_mul(scale)
        .ok_or_else(|| format!("'{s}' is too large"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cli(args: &[&str]) -> Cli {
        Cli::try_parse_from(std::iter::once("graspd").chain(args.iter().copied())).unwrap()
    }

    #[test]
    fn flag_beats_file_beats_default() {
        let dir = std::env::temp_dir().join(format!("graspd-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("graspd.toml");
        std::fs::write(
            &path,
            "max_points = 1000\nrest_addr = \"127.0.0.1:9000\"\nlog_format = \"json\"\n",
        )
        .unwrap();
        let p = path.to_str().unwrap();
        let s = Settings::resolve(&cli(&["--config", p, "--max-points", "2000"])).unwrap();
        assert_eq!(s.max_points, 2000);
        assert_eq!(s.rest_addr, "127.0.0.1:9000".parse().unwrap());
        assert_eq!(s.log_format, LogFormat::Json);
        assert_eq!(s.grpc_addr, "0.0.0.0:50051".parse().unwrap());
        assert_eq!(s.max_message_bytes, 32 << 20);
        std::fs::write(&path, "bogus = 1\n").unwrap();
        assert!(matches!(
            Settings::resolve(&cli(&["--config", p])),
            Err(ConfigError::Parse { .. })
        ));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The iteration limit reaches the facade's limits; beyond the planner's own bound (or 0)
    /// it stops the start naming the setting.
    #[test]
    fn the_iteration_limit_is_a_setting() {
        let s = Settings::resolve(&cli(&["--max-iterations", "250000"])).unwrap();
        assert_eq!(s.limits().max_iterations, 250_000);
        assert_eq!(
            Settings::resolve(&cli(&[]))
                .unwrap()
                .limits()
                .max_iterations,
            crate::facade::DEFAULT_MAX_ITERATIONS
        );
        for bad in ["0", "20000000"] {
            match Settings::resolve(&cli(&["--max-iterations", bad])) {
                Err(ConfigError::Invalid { field, .. }) => assert_eq!(field, "max_iterations"),
                other => panic!("{bad}: {other:?}"),
            }
        }
    }

    #[test]
    fn hand_imports_and_hands_dir() {
        let s = Settings::resolve(&cli(&[
            "--hands-dir",
            "/tmp/h",
            "--import-hand",
            "allegro=a/right_hand.xml",
            "--import-hand",
            "gripper=b.urdf",
        ]))
        .unwrap();
        let setup = s.hand_setup();
        assert_eq!(setup.hands_dir, Some(PathBuf::from("/tmp/h")));
        assert_eq!(
            setup.imports,
            vec![
                ("allegro".to_string(), PathBuf::from("a/right_hand.xml")),
                ("gripper".to_string(), PathBuf::from("b.urdf"))
            ]
        );
        assert!(Cli::try_parse_from(["graspd", "--import-hand", "nopath"]).is_err());
    }

    #[test]
    fn queue_and_tokens() {
        let s = Settings::resolve(&cli(&["--max-concurrent-plans", "3"])).unwrap();
        assert_eq!(s.max_queued_plans, 12);
        assert!(s.auth_tokens.is_empty());
        let dir = std::env::temp_dir().join(format!("graspd-tokens-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tokens = dir.join("tokens");
        std::fs::write(&tokens, "# fleet\nfile-token\n").unwrap();
        let config = dir.join("graspd.toml");
        std::fs::write(
            &config,
            "auth_tokens = [\"file-a\", \"file-b\"]\nmax_queued_plans = 0\n",
        )
        .unwrap();
        let c = config.to_str().unwrap();
        let t = tokens.to_str().unwrap();
        let s = Settings::resolve(&cli(&["--config", c])).unwrap();
        assert_eq!((s.auth_tokens.len(), s.max_queued_plans), (2, 0));
        let s = Settings::resolve(&cli(&[
            "--config",
            c,
            "--auth-token",
            "flag-token",
            "--auth-tokens-file",
            t,
        ]))
        .unwrap();
        assert_eq!(s.auth_tokens.len(), 2);
        assert!(s.auth_tokens.accepts(Some(b"Bearer flag-token")));
        assert!(s.auth_tokens.accepts(Some(b"Bearer file-token")));
        assert!(!s.auth_tokens.accepts(Some(b"Bearer file-a")));
        let printed = toml::to_string(&s).unwrap();
        assert!(
            !printed.contains("token\"") && !printed.contains("flag-token"),
            "{printed}"
        );
        assert!(!format!("{s:?}").contains("flag-token"));
        assert!(Settings::resolve(&cli(&["--auth-token", "a b"])).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn tls_files_come_in_pairs_and_print_as_paths() {
        assert_eq!(Settings::resolve(&cli(&[])).unwrap().tls_files(), None);
        let s = Settings::resolve(&cli(&[
            "--tls-cert",
            "/etc/graspd/cert.pem",
            "--tls-key",
            "/etc/graspd/key.pem",
        ]))
        .unwrap();
        let files = s.tls_files().unwrap();
        assert_eq!(files.key, PathBuf::from("/etc/graspd/key.pem"));
        assert_eq!(files.client_ca, None);
        let printed = toml::to_string(&s).unwrap();
        assert!(
            printed.contains("tls_key = \"/etc/graspd/key.pem\""),
            "{printed}"
        );
        for lonely in [
            &["--tls-cert", "c.pem"][..],
            &["--tls-key", "k.pem"],
            &["--tls-client-ca", "ca.pem"],
        ] {
            let e = Settings::resolve(&cli(lonely)).unwrap_err().to_string();
            assert!(e.contains(lonely[0]) && e.contains(lonely[1]), "{e}");
        }
        let dir = std::env::temp_dir().join(format!("graspd-tls-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let config = dir.join("graspd.toml");
        std::fs::write(
            &config,
            "tls_cert = \"c.pem\"\ntls_key = \"k.pem\"\ntls_client_ca = \"ca.pem\"\n",
        )
        .unwrap();
        let s = Settings::resolve(&cli(&["--config", config.to_str().unwrap()])).unwrap();
        assert_eq!(
            s.tls_files().unwrap().client_ca,
            Some(PathBuf::from("ca.pem"))
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn byte_counts() {
        assert_eq!(parse_bytes("4096"), Ok(4096));
        assert_eq!(parse_bytes("32MiB"), Ok(32 << 20));
        assert_eq!(parse_bytes("2K"), Ok(2048));
        assert!(parse_bytes("12 parsecs").is_err());
        assert!(Settings::resolve(&cli(&["--max-message-bytes", "10"])).is_err());
    }
}
