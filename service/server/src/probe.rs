//! `graspd --probe`: the container HEALTHCHECK. Asks the server that the same configuration
//! (flags, environment, config file) describes whether it is ready — `GET /readyz` on its probe
//! port when it has one, else on its REST port, over TLS when TLS is configured — and succeeds
//! on 200. The certificate is not verified: the probe talks to its own process on loopback, and
//! the address it dials (127.0.0.1) is rarely a name the certificate carries. With mutual TLS
//! the REST port wants a client certificate, which the probe does not have: give the server a
//! `--probe-addr` then.

use crate::config::Settings;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_rustls::rustls::client::danger::{
    HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier,
};
use tokio_rustls::rustls::pki_types::{CertificateDer, ServerName, UnixTime};
use tokio_rustls::rustls::{self, ClientConfig, DigitallySignedStruct, SignatureScheme};

/// The whole probe, connection to answer.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(3);

/// Probes the configured server (module doc): Ok when ready, else why not.
pub fn probe(settings: &Settings) -> Result<(), String> {
    let (addr, tls) = match settings.probe_addr {
        Some(a) => (a, false),
        None => (settings.rest_addr, settings.tls_files().is_some()),
    };
    let addr = dialable(addr);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))?;
    runtime.block_on(async {
        tokio::time::timeout(PROBE_TIMEOUT, ask(addr, tls))
            .await
            .map_err(|_| format!("{addr}: no answer within {PROBE_TIMEOUT:?}"))?
    })
}

/// A listening address as a probe dials it: the unspecified address is this host's loopback.
fn dialable(addr: SocketAddr) -> SocketAddr {
    match addr.ip() {
        IpAddr::V4(ip) if ip.is_unspecified() => (Ipv4Addr::LOCALHOST, addr.port()).into(),
        IpAddr::V6(ip) if ip.is_unspecified() => (Ipv6Addr::LOCALHOST, addr.port()).into(),
        _ => addr,
    }
}

async fn ask(addr: SocketAddr, tls: bool) -> Result<(), String> {
    let tcp = TcpStream::connect(addr)
        .await
        .map_err(|e| format!("{addr}: {e}"))?;
    if !tls {
        return readyz(tcp, addr).await;
    }
    let config =
        ClientConfig::builder_with_provider(Arc::new(rustls::crypto::ring::default_provider()))
            .with_safe_default_protocol_versions()
            .map_err(|e| e.to_string())?
            .dangerous()
            .with_custom_certificate_verifier(Arc::new(NoVerification))
            .with_no_client_auth();
    let name = ServerName::IpAddress(addr.ip().into());
    let stream = tokio_rustls::TlsConnector::from(Arc::new(config))
        .connect(name, tcp)
        .await
        .map_err(|e| format!("{addr}: TLS handshake failed: {e}"))?;
    readyz(stream, addr).await
}

/// `GET /readyz` over HTTP/1.1; Ok on status 200.
async fn readyz(
    mut io: impl AsyncRead + AsyncWrite + Unpin,
    addr: SocketAddr,
) -> Result<(), String> {
    io.write_all(b"GET /readyz HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
        .await
        .map_err(|e| format!("{addr}: {e}"))?;
    let mut head = Vec::new();
    let mut buf = [0u8; 256];
    while !head.contains(&b'\n') && head.len() < 4096 {
        let n = io
            .read(&mut buf)
            .await
            .map_err(|e| format!("{addr}: {e}"))?;
        if n == 0 {
            break;
        }
        head.extend_from_slice(&buf[..n]);
    }
    let line = String::from_utf8_lossy(&head);
    let line = line.lines().next().unwrap_or("");
    match line.split_whitespace().nth(1) {
        Some("200") => Ok(()),
        _ => Err(format!("{addr}: /readyz answered {line:?}")),
    }
}

/// Accepts any server certificate (module doc: the probe dials its own process).
#[derive(Debug)]
struct NoVerification;

impl ServerCertVerifier for NoVerification {
    fn verify_server_cert(
        &self,
        _: &CertificateDer<'_>,
        _: &[CertificateDer<'_>],
        _: &ServerName<'_>,
        _: &[u8],
        _: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        Ok(ServerCertVerified::assertion())
    }

    fn verify_tls12_signature(
        &self,
        _: &[u8],
        _: &CertificateDer<'_>,
        _: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        Ok(HandshakeSignatureValid::assertion())
    }

    fn verify_tls13_signature(
        &self,
        _: &[u8],
        _: &CertificateDer<'_>,
        _: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        Ok(HandshakeSignatureValid::assertion())
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        rustls::crypto::ring::default_provider()
            .signature_verification_algorithms
            .supported_schemes()
    }
}
