//! Starts both transports over one facade, announces the bound addresses, and shuts both down
//! gracefully on a signal.

use crate::config::Settings;
use crate::facade::GraspService;
use crate::ops::{Ops, ReadyState};
use crate::runner::PlanRunner;
use crate::tls::{Listening, Tls, TlsError};
use crate::{grpc, rest};
use graspd_core::onnx_runtime::init_onnx_runtime;
use graspd_core::perception::{GraspTypeModel, RecognitionModel};
use graspd_core::planning::grasp_quality::GraspQualityModel;
use graspd_core::tactile::{TactileModel, TactileModelError};
use std::future::Future;
use std::io::Write;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use thiserror::Error;
use tokio::net::TcpListener;
use tokio::sync::watch;

/// How long in-flight requests may take to finish after a shutdown signal.
pub const DRAIN_TIMEOUT: Duration = Duration::from_secs(30);

#[derive(Debug, Error)]
pub enum ServeError {
    #[error("cannot listen for {what} on {addr}: {source}")]
    Bind {
        what: &'static str,
        addr: SocketAddr,
        source: std::io::Error,
    },
    #[error("cannot announce the listening addresses: {0}")]
    Announce(std::io::Error),
    #[error("gRPC server: {0}")]
    Grpc(#[from] tonic::transport::Error),
    #[error("REST server: {0}")]
    Rest(std::io::Error),
    #[error("cannot load the hands: {0}")]
    Hands(String),
    #[error("cannot load the tactile calibrations: {0}")]
    Calibrations(String),
    #[error("cannot load the {what}: {reason}")]
    Model { what: &'static str, reason: String },
    #[error("TLS: {0}")]
    Tls(#[from] TlsError),
    #[error("server task failed: {0}")]
    Task(#[from] tokio::task::JoinError),
}

async fn bind(what: &'static str, addr: SocketAddr) -> Result<TcpListener, ServeError> {
    TcpListener::bind(addr)
        .await
        .map_err(|source| ServeError::Bind { what, addr, source })
}

/// The shipped models (models/grasp_type/grasp_type.onnx, about 1.4 MB, and
/// models/tactile/tactile_detector.onnx, about 130 KB), built into the binary so that a bare
/// `graspd` has them.
const EMBEDDED_GRASP_TYPE_MODEL: &[u8] =
    include_bytes!("../../../models/grasp_type/grasp_type.onnx");
const EMBEDDED_GRASP_TYPE_NAME: &str = "built-in models/grasp_type/grasp_type.onnx";
const EMBEDDED_TACTILE_MODEL: &[u8] =
    include_bytes!("../../../models/tactile/tactile_detector.onnx");
const EMBEDDED_TACTILE_NAME: &str = "built-in models/tactile/tactile_detector.onnx";
/// models/recogniser/recogniser.onnx (about 1 MB).
const EMBEDDED_RECOGNISER_MODEL: &[u8] =
    include_bytes!("../../../models/recogniser/recogniser.onnx");
const EMBEDDED_RECOGNISER_NAME: &str = "built-in models/recogniser/recogniser.onnx";
/// models/grasp_quality/grasp_quality.onnx (about 0.5 MB).
const EMBEDDED_GRASP_QUALITY_MODEL: &[u8] =
    include_bytes!("../../../models/grasp_quality/grasp_quality.onnx");
const EMBEDDED_GRASP_QUALITY_NAME: &str = "built-in models/grasp_quality/grasp_quality.onnx";

/// Loads a model the same way for both: a configured file must load (else the start fails);
/// with none configured the built-in copy is loaded (`load(None)`), and if that fails (e.g. no
/// ONNX Runtime) graspd warns and runs without (`fallback` says what it does instead); `none`
/// loads nothing.
fn load_model<M, E: std::fmt::Display>(
    what: &'static str,
    configured: Option<&std::path::Path>,
    fallback: &str,
    load: impl FnOnce(Option<&std::path::Path>) -> Result<M, E>,
) -> Result<Option<M>, ServeError> {
    let load = |path| tokio::task::block_in_place(|| load(path));
    match configured {
        Some(p) if p.as_os_str() == "none" => {
            tracing::info!("no {what} (set to none): {fallback}");
            Ok(None)
        }
        Some(path) => load(Some(path)).map(Some).map_err(|e| ServeError::Model {
            what,
            reason: e.to_string(),
        }),
        None => match load(None) {
            Ok(m) => Ok(Some(m)),
            Err(e) => {
                tracing::warn!(error = %e, "the built-in {what} is not loaded: {fallback}");
                Ok(None)
            }
        },
    }
}

fn with_models(service: GraspService, settings: &Settings) -> Result<GraspService, ServeError> {
    let runtime = settings.onnxruntime.as_deref();
    let mut service = service;
    if let Some(model) = load_model(
        "grasp-type model",
        settings.grasp_type_model.as_deref(),
        "the geometric rule decides grasp types",
        |path| {
            init_onnx_runtime(runtime)?;
            match path {
                Some(p) => GraspTypeModel::load(p, settings.model_threads),
                None => GraspTypeModel::from_bytes(
                    EMBEDDED_GRASP_TYPE_MODEL,
                    EMBEDDED_GRASP_TYPE_NAME,
                    settings.model_threads,
                ),
            }
        },
    )? {
        tracing::info!(
            source = %model.path().display(),
            channels = model.channels(),
            "grasp-type model loaded"
        );
        service = service.with_grasp_type_model(Arc::new(model));
    }
    if let Some(model) = load_model(
        "recogniser",
        settings.recogniser_model.as_deref(),
        "hints.object is refused",
        |path| {
            init_onnx_runtime(runtime)?;
            match path {
                Some(p) => RecognitionModel::load(p, settings.model_threads),
                None => RecognitionModel::from_bytes(
                    EMBEDDED_RECOGNISER_MODEL,
                    EMBEDDED_RECOGNISER_NAME,
                    settings.model_threads,
                ),
            }
        },
    )? {
        tracing::info!(
            source = %model.path().display(),
            classes = model.classes().len(),
            "recogniser loaded"
        );
        service = service.with_recogniser(Arc::new(model));
    }
    if let Some(model) = load_model(
        "grasp-quality model",
        settings.grasp_quality_model.as_deref(),
        "options.mode = learned_quality is refused",
        |path| {
            init_onnx_runtime(runtime)?;
            match path {
                Some(p) => GraspQualityModel::load(p, settings.model_threads),
                None => GraspQualityModel::from_bytes(
                    EMBEDDED_GRASP_QUALITY_MODEL,
                    EMBEDDED_GRASP_QUALITY_NAME,
                    settings.model_threads,
                ),
            }
        },
    )? {
        tracing::info!(
            source = %model.path().display(),
            "grasp-quality model loaded"
        );
        service = service.with_grasp_quality(Arc::new(model));
    }
    if let Some(model) = load_model(
        "tactile model",
        settings.tactile_model.as_deref(),
        "tactile sessions use the model-free detector",
        |path| {
            init_onnx_runtime(runtime).map_err(TactileModelError::Runtime)?;
            match path {
                Some(p) => TactileModel::load(p),
                None => TactileModel::from_bytes(EMBEDDED_TACTILE_MODEL, EMBEDDED_TACTILE_NAME),
            }
        },
    )? {
        tracing::info!(
            source = model.source_name(),
            window = model.window_length(),
            stride = model.stride(),
            electrodes = model.electrode_count(),
            "tactile model loaded"
        );
        service = service.with_tactile_model(Arc::new(model));
    }
    Ok(service)
}

/// Binds both listeners, prints `graspd listening grpc=ADDR rest=ADDR` on stdout (tests read
/// it to find ephemeral ports), serves until `shutdown` completes, then drains both.
pub async fn run(
    settings: &Settings,
    shutdown: impl Future<Output = ()> + Send,
) -> Result<(), ServeError> {
    // Hands first: a model that cannot be read fails the start before anything listens.
    let service = tokio::task::block_in_place(|| {
        GraspService::with_hands(settings.limits(), &settings.hand_setup())
    })
    .map_err(ServeError::Hands)?;
    let service = match &settings.calibrations_dir {
        Some(dir) => tokio::task::block_in_place(|| service.with_calibrations_dir(dir.clone()))
            .map_err(ServeError::Calibrations)?,
        None => service,
    };
    let service = with_models(service, settings)?;
    // TLS files next: one that cannot be read, or a key that does not match, fails the start.
    let tls = settings.tls_files().map(|f| Tls::load(&f)).transpose()?;
    let grpc_listener = bind("gRPC", settings.grpc_addr).await?;
    let rest_listener = bind("REST", settings.rest_addr).await?;
    let grpc_addr = grpc_listener.local_addr().map_err(ServeError::Announce)?;
    let rest_addr = rest_listener.local_addr().map_err(ServeError::Announce)?;

    let ops = Ops::new(settings.auth_tokens.clone());
    let runner = PlanRunner::new(service, ops.metrics.clone());
    let (stop, stopped) = watch::channel(());
    let wait = |mut rx: watch::Receiver<()>| async move {
        let _ = rx.changed().await;
    };
    // Hands and models are loaded and both ports bound: ready (the servers, spawned next, start
    // from this state, so the first probe already sees it).
    ops.readiness.set(ReadyState::Ready);
    let grpc_listening = Listening::new(grpc_listener, tls.as_ref().map(|t| t.grpc.clone()))
        .map_err(ServeError::Announce)?;
    let rest_listening = Listening::new(rest_listener, tls.as_ref().map(|t| t.rest.clone()))
        .map_err(ServeError::Announce)?;
    if let Some(t) = &tls {
        t.watch();
    }
    let mut grpc_task = tokio::spawn(grpc::serve(
        grpc_listening,
        runner.clone(),
        ops.clone(),
        wait(stopped.clone()),
    ));
    let probe_addr = match settings.probe_addr {
        None => None,
        Some(addr) => {
            let listener = bind("probe", addr).await?;
            let local = listener.local_addr().map_err(ServeError::Announce)?;
            let wait = wait(stopped.clone());
            let ops = ops.clone();
            tokio::spawn(async move {
                if let Err(e) = rest::serve_probes(listener, ops, wait).await {
                    tracing::error!(error = %e, "the probe port stopped");
                }
            });
            Some(local)
        }
    };
    let mut rest_task = tokio::spawn(rest::serve(
        rest_listening,
        runner,
        ops.clone(),
        wait(stopped),
    ));

    {
        let mut out = std::io::stdout().lock();
        let probe = probe_addr.map_or(String::new(), |a| format!(" probe={a}"));
        writeln!(
            out,
            "graspd listening grpc={grpc_addr} rest={rest_addr}{probe}"
        )
        .and_then(|()| out.flush())
        .map_err(ServeError::Announce)?;
    }
    tracing::info!(
        %grpc_addr,
        %rest_addr,
        probe_addr = probe_addr.map(|a| a.to_string()),
        max_message_bytes = settings.max_message_bytes,
        max_points = settings.max_points,
        max_concurrent_plans = settings.max_concurrent_plans,
        max_queued_plans = settings.max_queued_plans,
        auth_tokens = settings.auth_tokens.len(),
        max_tactile_sessions = settings.max_tactile_sessions,
        tls = tls.is_some(),
        mutual_tls = tls.as_ref().is_some_and(|t| t.mutual),
        "graspd listening"
    );

    tokio::select! {
        () = shutdown => {}
        r = &mut grpc_task => {
            r??;
            tracing::warn!("the gRPC server stopped by itself");
        }
        r = &mut rest_task => {
            r?.map_err(ServeError::Rest)?;
            tracing::warn!("the REST server stopped by itself");
        }
    }
    tracing::info!("shutting down: draining in-flight requests");
    ops.readiness.set(ReadyState::Draining);
    if settings.drain_delay_ms > 0 {
        // Still serving, but not ready: load balancers take the instance out first.
        tokio::time::sleep(Duration::from_millis(settings.drain_delay_ms)).await;
    }
    let _ = stop.send(());
    let drained = tokio::time::timeout(DRAIN_TIMEOUT, async {
        if !grpc_task.is_finished() {
            (&mut grpc_task).await??;
        }
        if !rest_task.is_finished() {
            (&mut rest_task).await?.map_err(ServeError::Rest)?;
        }
        Ok::<(), ServeError>(())
    })
    .await;
    match drained {
        Ok(result) => result?,
        Err(_) => tracing::warn!(
            "requests still open after {}s; stopping anyway",
            DRAIN_TIMEOUT.as_secs()
        ),
    }
    tracing::info!("stopped");
    Ok(())
}

/// Installs the handlers of Ctrl-C (SIGINT) and SIGTERM now, and returns a future that
/// completes on either. Call it inside the runtime, before `run` binds anything: a handler
/// installed only when the future is first polled (`tokio::signal::ctrl_c`) left a gap after
/// the servers were spawned, in which a signal killed the process instead of draining it (the
/// lifecycle test's SIGINT right after a `/healthz` answer, on a loaded two-core machine).
pub fn shutdown_signal() -> impl Future<Output = ()> + Send {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{Signal, SignalKind, signal};
        let interrupt = signal(SignalKind::interrupt()).ok();
        let terminate = signal(SignalKind::terminate()).ok();
        let received = |s: Option<Signal>| async move {
            match s {
                Some(mut s) => {
                    s.recv().await;
                }
                None => std::future::pending::<()>().await,
            }
        };
        async move {
            tokio::select! {
                () = received(interrupt) => tracing::info!("received Ctrl-C"),
                () = received(terminate) => tracing::info!("received SIGTERM"),
            }
        }
    }
    #[cfg(not(unix))]
    async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
        tracing::info!("received Ctrl-C");
    }
}
