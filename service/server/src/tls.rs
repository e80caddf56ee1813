//! Optional TLS for both ports (rustls with ring; no OpenSSL), and optional mutual TLS.
//!
//! [`Tls::load`] reads and checks the PEM files once, before anything listens: a file that
//! cannot be read or parsed, or a key that does not match the certificate, stops the start with
//! a message naming the flag and the file (never the key's contents). Both ports accept through
//! a [`TlsListener`] that completes handshakes off the accept loop (REST hands the finished TLS
//! streams to `axum::serve`, which keeps its graceful shutdown and HTTP/1.1 upgrades; gRPC to
//! tonic's `serve_with_incoming`).
//!
//! Certificates are reloaded without a restart ([`Tls::reload`]): on SIGHUP and when one of the
//! files changes (checked every [`WATCH_INTERVAL`]; cert-manager and similar tools replace the
//! files in place). Each handshake takes the configuration current when it starts, so open
//! connections keep theirs and are not dropped. A reload whose files fail the start's checks
//! is logged and changes nothing: the server goes on with the certificate it had.

use axum::serve::Listener;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};
use std::time::{Duration, SystemTime};
use thiserror::Error;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::mpsc;
use tokio_rustls::TlsAcceptor;
use tokio_rustls::rustls;
use tokio_rustls::rustls::crypto::{CryptoProvider, ring};
use tokio_rustls::rustls::pki_types::pem::PemObject;
use tokio_rustls::rustls::pki_types::{CertificateDer, PrivateKeyDer};
use tokio_rustls::rustls::server::WebPkiClientVerifier;
use tokio_rustls::rustls::{RootCertStore, ServerConfig};
use tokio_rustls::server::TlsStream;

/// How long a client may take to complete its TLS handshake.
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(10);

/// The flags, as error messages name them.
pub const CERT_FLAG: &str = "--tls-cert";
pub const KEY_FLAG: &str = "--tls-key";
pub const CLIENT_CA_FLAG: &str = "--tls-client-ca";

/// The configured PEM files (paths only; `--print-config` prints these).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlsFiles {
    pub cert: PathBuf,
    pub key: PathBuf,
    /// With it, clients must present a certificate signed by this CA (mutual TLS).
    pub client_ca: Option<PathBuf>,
}

#[derive(Debug, Error)]
#[error("{flag} {}: {message}", path.display())]
pub struct TlsError {
    pub flag: &'static str,
    pub path: PathBuf,
    pub message: String,
}

fn error(flag: &'static str, path: &Path, message: impl Into<String>) -> TlsError {
    TlsError {
        flag,
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// How often the certificate files are checked for changes.
pub const WATCH_INTERVAL: Duration = Duration::from_secs(2);

/// A server configuration that a reload replaces; each handshake reads the current one.
#[derive(Clone)]
pub struct Reloadable(Arc<RwLock<Arc<ServerConfig>>>);

impl Reloadable {
    fn new(config: ServerConfig) -> Self {
        Self(Arc::new(RwLock::new(Arc::new(config))))
    }

    /// The configuration for the next handshake.
    pub fn current(&self) -> Arc<ServerConfig> {
        self.0.read().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn replace(&self, config: ServerConfig) {
        *self.0.write().unwrap_or_else(|e| e.into_inner()) = Arc::new(config);
    }
}

/// The loaded and checked TLS setup of both ports.
#[derive(Clone)]
pub struct Tls {
    files: TlsFiles,
    /// The REST port's configuration (ALPN h2 and http/1.1).
    pub rest: Reloadable,
    /// The gRPC port's (ALPN h2): the same certificate, key and client CA.
    pub grpc: Reloadable,
    /// Whether client certificates are required.
    pub mutual: bool,
}

impl std::fmt::Debug for Tls {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tls")
            .field("mutual", &self.mutual)
            .finish_non_exhaustive()
    }
}

fn read(flag: &'static str, path: &Path) -> Result<Vec<u8>, TlsError> {
    std::fs::read(path).map_err(|e| error(flag, path, format!("cannot read: {e}")))
}

fn certificates(
    flag: &'static str,
    path: &Path,
    pem: &[u8],
) -> Result<Vec<CertificateDer<'static>>, TlsError> {
    let certs = CertificateDer::pem_slice_iter(pem)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| error(flag, path, format!("not a PEM certificate file: {e}")))?;
    if certs.is_empty() {
        return Err(error(
            flag,
            path,
            "holds no PEM certificate (BEGIN CERTIFICATE)",
        ));
    }
    Ok(certs)
}

fn provider() -> Arc<CryptoProvider> {
    Arc::new(ring::default_provider())
}

impl Tls {
    /// Reads and checks the files; builds both ports' configurations.
    pub fn load(files: &TlsFiles) -> Result<Self, TlsError> {
        let rest = server_config(files)?;
        let mut grpc = rest.clone();
        grpc.alpn_protocols = vec![b"h2".to_vec()];
        Ok(Tls {
            files: files.clone(),
            rest: Reloadable::new(rest),
            grpc: Reloadable::new(grpc),
            mutual: files.client_ca.is_some(),
        })
    }

    /// Reads the files again; with every check of [`Tls::load`] passed, new handshakes on both
    /// ports use them (open connections keep theirs). On error nothing changes.
    pub fn reload(&self) -> Result<(), TlsError> {
        let rest = server_config(&self.files)?;
        let mut grpc = rest.clone();
        grpc.alpn_protocols = vec![b"h2".to_vec()];
        self.rest.replace(rest);
        self.grpc.replace(grpc);
        Ok(())
    }

    /// Reloads on SIGHUP and whenever a file's modification time or size changes (polled every
    /// [`WATCH_INTERVAL`]); logs each reload and each refused one. Runs until the runtime ends.
    pub fn watch(&self) {
        let tls = self.clone();
        tokio::spawn(async move {
            let mut seen = tls.stamps();
            #[cfg(unix)]
            let mut hangup =
                tokio::signal::unix::signal(tokio::signal::unix::SignalKind::hangup()).ok();
            loop {
                #[cfg(unix)]
                let why = match hangup.as_mut() {
                    Some(h) => tokio::select! {
                        _ = h.recv() => "SIGHUP",
                        () = tokio::time::sleep(WATCH_INTERVAL) => "file change",
                    },
                    None => {
                        tokio::time::sleep(WATCH_INTERVAL).await;
                        "file change"
                    }
                };
                #[cfg(not(unix))]
                let why = {
                    tokio::time::sleep(WATCH_INTERVAL).await;
                    "file change"
                };
                let now = tls.stamps();
                if why == "file change" && now == seen {
                    continue;
                }
                seen = now;
                match tls.reload() {
                    Ok(()) => tracing::info!(trigger = why, "TLS certificates reloaded"),
                    Err(e) => tracing::error!(
                        trigger = why,
                        error = %e,
                        "TLS certificates not reloaded; serving the previous ones"
                    ),
                }
            }
        });
    }

    /// Each file's modification time and size (None when unreadable).
    fn stamps(&self) -> Vec<Option<(SystemTime, u64)>> {
        [
            Some(&self.files.cert),
            Some(&self.files.key),
            self.files.client_ca.as_ref(),
        ]
        .into_iter()
        .flatten()
        .map(|p| {
            std::fs::metadata(p)
                .ok()
                .and_then(|m| Some((m.modified().ok()?, m.len())))
        })
        .collect()
    }
}

/// The REST port's configuration from the files (ALPN h2 and http/1.1): every check of the start.
fn server_config(files: &TlsFiles) -> Result<ServerConfig, TlsError> {
    let cert_pem = read(CERT_FLAG, &files.cert)?;
    let certs = certificates(CERT_FLAG, &files.cert, &cert_pem)?;
    let key_pem = read(KEY_FLAG, &files.key)?;
    // The parse error names the PEM section at most, never the key material.
    let key = PrivateKeyDer::from_pem_slice(&key_pem).map_err(|e| {
        error(
            KEY_FLAG,
            &files.key,
            format!("not a PEM private key (PKCS#8, PKCS#1 or SEC1): {e}"),
        )
    })?;
    let provider = provider();
    let builder = ServerConfig::builder_with_provider(provider.clone())
        .with_safe_default_protocol_versions()
        .map_err(|e| error(CERT_FLAG, &files.cert, e.to_string()))?;
    let builder = match &files.client_ca {
        None => builder.with_no_client_auth(),
        Some(ca_path) => {
            let ca_pem = read(CLIENT_CA_FLAG, ca_path)?;
            let mut roots = RootCertStore::empty();
            for cert in certificates(CLIENT_CA_FLAG, ca_path, &ca_pem)? {
                roots.add(cert).map_err(|e| {
                    error(
                        CLIENT_CA_FLAG,
                        ca_path,
                        format!("not a usable CA certificate: {e}"),
                    )
                })?;
            }
            let verifier = WebPkiClientVerifier::builder_with_provider(Arc::new(roots), provider)
                .build()
                .map_err(|e| error(CLIENT_CA_FLAG, ca_path, e.to_string()))?;
            builder.with_client_cert_verifier(verifier)
        }
    };
    let mut config = builder.with_single_cert(certs, key).map_err(|e| match e {
        rustls::Error::InconsistentKeys(_) => error(
            KEY_FLAG,
            &files.key,
            format!(
                "does not match the certificate of {CERT_FLAG} {}",
                files.cert.display()
            ),
        ),
        rustls::Error::InvalidCertificate(e) => error(
            CERT_FLAG,
            &files.cert,
            format!("not a usable certificate: {e:?}"),
        ),
        e => error(KEY_FLAG, &files.key, format!("unusable private key: {e}")),
    })?;
    config.alpn_protocols = vec![b"h2".to_vec(), b"http/1.1".to_vec()];
    Ok(config)
}

/// A port's listener: plain TCP, or TLS.
pub enum Listening {
    Plain(TcpListener),
    Tls(TlsListener),
}

impl Listening {
    /// `listener` as is, or behind TLS with `config`.
    pub fn new(listener: TcpListener, config: Option<Reloadable>) -> std::io::Result<Self> {
        Ok(match config {
            None => Self::Plain(listener),
            Some(c) => Self::Tls(TlsListener::new(listener, c)?),
        })
    }
}

/// A TLS listener (for `axum::serve`, and as a stream for tonic): a task accepts TCP
/// connections and completes each handshake in its own task (with [`HANDSHAKE_TIMEOUT`]) with
/// the configuration current then, so a slow or failed handshake holds up no one; failed
/// handshakes are logged at debug and dropped. When the server stops accepting (graceful
/// shutdown) and drops the listener, the accept task ends and the port closes.
pub struct TlsListener {
    ready: mpsc::Receiver<(TlsStream<TcpStream>, SocketAddr)>,
    local_addr: SocketAddr,
}

impl TlsListener {
    pub fn new(listener: TcpListener, config: Reloadable) -> std::io::Result<Self> {
        let local_addr = listener.local_addr()?;
        let (tx, ready) = mpsc::channel(64);
        tokio::spawn(async move {
            loop {
                let (tcp, peer) = tokio::select! {
                    () = tx.closed() => break,
                    accepted = listener.accept() => match accepted {
                        Ok(accepted) => accepted,
                        Err(e) => {
                            accept_error(e).await;
                            continue;
                        }
                    },
                };
                let _ = tcp.set_nodelay(true);
                let acceptor = TlsAcceptor::from(config.current());
                let tx = tx.clone();
                tokio::spawn(async move {
                    match tokio::time::timeout(HANDSHAKE_TIMEOUT, acceptor.accept(tcp)).await {
                        Ok(Ok(stream)) => {
                            let _ = tx.send((stream, peer)).await;
                        }
                        Ok(Err(e)) => tracing::debug!(%peer, error = %e, "TLS handshake failed"),
                        Err(_) => tracing::debug!(%peer, "TLS handshake timed out"),
                    }
                });
            }
        });
        Ok(Self { ready, local_addr })
    }
}

/// As axum's own listener: errors of one connection are skipped; others (e.g. too many open
/// files) are logged and retried after a second.
async fn accept_error(e: std::io::Error) {
    use std::io::ErrorKind::{ConnectionAborted, ConnectionRefused, ConnectionReset};
    if matches!(
        e.kind(),
        ConnectionRefused | ConnectionAborted | ConnectionReset
    ) {
        return;
    }
    tracing::error!(error = %e, "REST accept failed");
    tokio::time::sleep(Duration::from_secs(1)).await;
}

impl TlsListener {
    /// The accepted TLS streams as a stream (tonic's `serve_with_incoming`).
    pub fn into_stream(
        self,
    ) -> impl tokio_stream::Stream<Item = std::io::Result<TlsStream<TcpStream>>> {
        use tokio_stream::StreamExt;
        tokio_stream::wrappers::ReceiverStream::new(self.ready).map(|(io, _)| Ok(io))
    }
}

impl Listener for TlsListener {
    type Io = TlsStream<TcpStream>;
    type Addr = SocketAddr;

    async fn accept(&mut self) -> (Self::Io, Self::Addr) {
        match self.ready.recv().await {
            Some(accepted) => accepted,
            // The accept task never ends while this receiver lives.
            None => std::future::pending().await,
        }
    }

    fn local_addr(&self) -> std::io::Result<Self::Addr> {
        Ok(self.local_addr)
    }
}
