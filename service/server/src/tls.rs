//! Optional TLS for both ports (rustls with ring; no OpenSSL), and optional mutual TLS.
//!
//! [`Tls::load`] reads and checks the PEM files once, before anything listens: a file that
//! cannot be read or parsed, or a key that does not match the certificate, stops the start with
//! a message naming the flag and the file (never the key's contents). The gRPC port gets the same
//! files through tonic's own rustls acceptor ([`Tls::grpc`]); the REST port gets a
//! [`TlsListener`] that completes handshakes off the accept loop and hands finished TLS streams
//! to `axum::serve`, which keeps its graceful shutdown and HTTP/1.1 upgrades (WebSockets).

use axum::serve::Listener;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
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

/// The loaded and checked TLS setup of both ports.
#[derive(Clone)]
pub struct Tls {
    /// The REST port's rustls configuration (ALPN h2 and http/1.1).
    pub rest: Arc<ServerConfig>,
    /// The gRPC port's configuration for tonic (the same certificate, key and client CA).
    pub grpc: tonic::transport::ServerTlsConfig,
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
        let mut grpc = tonic::transport::ServerTlsConfig::new()
            .identity(tonic::transport::Identity::from_pem(&cert_pem, &key_pem));
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
                let verifier =
                    WebPkiClientVerifier::builder_with_provider(Arc::new(roots), provider)
                        .build()
                        .map_err(|e| error(CLIENT_CA_FLAG, ca_path, e.to_string()))?;
                grpc = grpc.client_ca_root(tonic::transport::Certificate::from_pem(&ca_pem));
                builder.with_client_cert_verifier(verifier)
            }
        };
        let mut rest = builder.with_single_cert(certs, key).map_err(|e| match e {
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
        rest.alpn_protocols = vec![b"h2".to_vec(), b"http/1.1".to_vec()];
        Ok(Tls {
            rest: Arc::new(rest),
            grpc: grpc.timeout(HANDSHAKE_TIMEOUT),
            mutual: files.client_ca.is_some(),
        })
    }
}

/// A TLS listener for `axum::serve`: a task accepts TCP connections and completes each
/// handshake in its own task (with [`HANDSHAKE_TIMEOUT`]), so a slow or failed handshake holds
/// up no one; failed handshakes are logged at debug and dropped. When axum stops accepting
/// (graceful shutdown) and drops the listener, the accept task ends and the port closes.
pub struct TlsListener {
    ready: mpsc::Receiver<(TlsStream<TcpStream>, SocketAddr)>,
    local_addr: SocketAddr,
}

impl TlsListener {
    pub fn new(listener: TcpListener, config: Arc<ServerConfig>) -> std::io::Result<Self> {
        let local_addr = listener.local_addr()?;
        let (tx, ready) = mpsc::channel(64);
        let acceptor = TlsAcceptor::from(config);
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
                let acceptor = acceptor.clone();
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
