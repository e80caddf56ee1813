//! TLS and mutual TLS on the real server (issue 8, item 3): a throwaway CA, a server certificate
//! for 127.0.0.1/localhost and client certificates are made at test time (rcgen). A TLS server
//! plans over gRPC and HTTPS REST (and its WebSocket) for a client that trusts the CA, and not
//! for one that does not or that speaks plain HTTP/2; with `--tls-client-ca` a client without a
//! CA-signed certificate is refused at the handshake; bad files stop the start naming the flag.

use futures_util::{SinkExt, StreamExt};
use graspd_e2e::{Server, binary, grpc_request, json_request};
use graspd_proto::v1::grasp_planner_client::GraspPlannerClient;
use rcgen::{
    BasicConstraints, CertificateParams, CertifiedIssuer, DnType, ExtendedKeyUsagePurpose, IsCa,
    KeyPair, KeyUsagePurpose,
};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::Duration;
use tokio_rustls::rustls;
use tokio_rustls::rustls::pki_types::pem::PemObject;
use tonic::transport::{Certificate, Channel, ClientTlsConfig, Identity};

/// Every network step of these tests ends within this, so a refusal cannot hang.
const STEP: Duration = Duration::from_secs(20);

/// A certificate and its key, PEM.
struct Pair {
    cert: String,
    key: String,
}

/// The files of one test: a CA, the server's certificate signed by it, a client certificate
/// signed by it and one signed by another CA, written under a fresh directory.
struct Pki {
    dir: PathBuf,
    ca: String,
    client: Pair,
    rogue_client: Pair,
}

fn ca(name: &str) -> CertifiedIssuer<'static, KeyPair> {
    let mut params = CertificateParams::new(Vec::<String>::new()).unwrap();
    params.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    params.distinguished_name.push(DnType::CommonName, name);
    params.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
    CertifiedIssuer::self_signed(params, KeyPair::generate().unwrap()).unwrap()
}

fn leaf(
    issuer: &CertifiedIssuer<'static, KeyPair>,
    names: &[&str],
    usage: ExtendedKeyUsagePurpose,
) -> Pair {
    let mut params =
        CertificateParams::new(names.iter().map(|n| n.to_string()).collect::<Vec<_>>()).unwrap();
    params.distinguished_name.push(
        DnType::CommonName,
        names.first().copied().unwrap_or("robot-7"),
    );
    params.extended_key_usages = vec![usage];
    let key = KeyPair::generate().unwrap();
    let cert = params.signed_by(&key, issuer).unwrap();
    Pair {
        cert: cert.pem(),
        key: key.serialize_pem(),
    }
}

impl Pki {
    fn new(test: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("graspd-tls-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let authority = ca("graspd test CA");
        let server = leaf(
            &authority,
            &["localhost", "127.0.0.1"],
            ExtendedKeyUsagePurpose::ServerAuth,
        );
        let client = leaf(&authority, &[], ExtendedKeyUsagePurpose::ClientAuth);
        let rogue_client = leaf(&ca("another CA"), &[], ExtendedKeyUsagePurpose::ClientAuth);
        // A valid key of another certificate, for the mismatch check.
        let other_key = KeyPair::generate().unwrap().serialize_pem();
        for (name, text) in [
            ("ca.pem", authority.pem()),
            ("server.pem", server.cert.clone()),
            ("server.key", server.key.clone()),
            ("other.key", other_key),
            ("garbage.pem", "not a certificate\n".to_string()),
        ] {
            std::fs::write(dir.join(name), text).unwrap();
        }
        Pki {
            dir,
            ca: authority.pem(),
            client,
            rogue_client,
        }
    }

    fn path(&self, name: &str) -> String {
        self.dir.join(name).to_str().unwrap().to_string()
    }

    /// Starts graspd with the server certificate (and `extra` flags).
    fn start(&self, extra: &[&str]) -> Server {
        let (cert, key) = (self.path("server.pem"), self.path("server.key"));
        let mut args = vec!["--tls-cert", &cert, "--tls-key", &key];
        args.extend_from_slice(extra);
        Server::start_with(&args)
    }
}

impl Drop for Pki {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

/// A gRPC client over TLS that trusts `ca` (none: no roots at all), with an optional client
/// certificate. Connecting is lazy: the handshake happens on the first call.
fn grpc_tls(
    server: &Server,
    ca: Option<&str>,
    identity: Option<&Pair>,
) -> GraspPlannerClient<Channel> {
    let mut tls = ClientTlsConfig::new();
    if let Some(ca) = ca {
        tls = tls.ca_certificate(Certificate::from_pem(ca));
    }
    if let Some(pair) = identity {
        tls = tls.identity(Identity::from_pem(&pair.cert, &pair.key));
    }
    let channel = Channel::from_shared(format!("https://{}", server.grpc_addr))
        .unwrap()
        .tls_config(tls)
        .unwrap()
        .connect_timeout(STEP)
        .timeout(STEP)
        .connect_lazy();
    GraspPlannerClient::new(channel)
}

/// An HTTPS client that trusts `ca` (none: only the built-in web roots), with an optional client
/// certificate.
fn https(ca: Option<&str>, identity: Option<&Pair>) -> reqwest::Client {
    let mut builder = reqwest::Client::builder().use_rustls_tls().timeout(STEP);
    if let Some(ca) = ca {
        builder =
            builder.add_root_certificate(reqwest::Certificate::from_pem(ca.as_bytes()).unwrap());
    }
    if let Some(pair) = identity {
        let pem = format!("{}{}", pair.cert, pair.key);
        builder = builder.identity(reqwest::Identity::from_pem(pem.as_bytes()).unwrap());
    }
    builder.build().unwrap()
}

async fn rest_plan(client: &reqwest::Client, server: &Server) -> Result<u16, reqwest::Error> {
    let response = client
        .post(format!("https://{}/v1/plan", server.rest_addr))
        .json(&json_request("shadow", 1))
        .send()
        .await?;
    Ok(response.status().as_u16())
}

async fn grpc_plan(mut client: GraspPlannerClient<Channel>) -> Result<String, tonic::Status> {
    let response = tokio::time::timeout(STEP, client.plan_grasp(grpc_request("shadow", 1)))
        .await
        .expect("a gRPC answer in time")?;
    Ok(response.into_inner().hand)
}

#[tokio::test]
async fn a_tls_server_plans_for_clients_that_trust_its_ca_and_no_others() {
    let pki = Pki::new("plain");
    let server = pki.start(&[]);

    // gRPC over TLS with the CA: a plan.
    let planned = grpc_plan(grpc_tls(&server, Some(&pki.ca), None)).await;
    assert!(planned.is_ok_and(|hand| hand == "shadow"), "gRPC over TLS");
    // HTTPS REST with the CA: a plan, and the probes.
    let client = https(Some(&pki.ca), None);
    assert_eq!(rest_plan(&client, &server).await.unwrap(), 200);
    let ready = client
        .get(format!("https://{}/readyz", server.rest_addr))
        .send()
        .await
        .unwrap();
    assert_eq!(ready.status(), 200);
    // The REST WebSocket over TLS (wss): a frame before the session is an error naming the field.
    let mut ws = wss(&server, &pki.ca).await;
    let frame = serde_json::json!({"frame": {"timestamp": 0.0, "fingers": []}});
    ws.send(tokio_tungstenite::tungstenite::Message::text(
        frame.to_string(),
    ))
    .await
    .unwrap();
    let answer = loop {
        match tokio::time::timeout(STEP, ws.next()).await.unwrap() {
            Some(Ok(tokio_tungstenite::tungstenite::Message::Text(t))) => {
                break serde_json::from_str::<serde_json::Value>(t.as_str()).unwrap();
            }
            Some(Ok(_)) => continue,
            other => panic!("expected an answer over wss, got {other:?}"),
        }
    };
    assert_eq!(answer["error"]["field"], "session", "{answer}");

    // Without the CA the handshakes fail: no roots (gRPC), only the web's roots (REST).
    let refused = grpc_plan(grpc_tls(&server, None, None)).await.unwrap_err();
    assert_eq!(refused.code(), tonic::Code::Unavailable, "{refused:?}");
    assert!(refused.message().contains("UnknownIssuer"), "{refused:?}");
    let error = rest_plan(&https(None, None), &server).await.unwrap_err();
    assert!(error.is_connect(), "{error:?}");

    // Plain HTTP/2 and HTTP against the TLS ports fail too.
    let plain = async {
        let mut client = GraspPlannerClient::connect(format!("http://{}", server.grpc_addr))
            .await
            .map_err(|e| e.to_string())?;
        client
            .plan_grasp(grpc_request("shadow", 1))
            .await
            .map_err(|e| e.to_string())
    };
    let plain = tokio::time::timeout(STEP, plain)
        .await
        .expect("an answer in time");
    assert!(plain.is_err(), "plain HTTP/2 against the TLS port planned");
    let plain = reqwest::Client::builder()
        .timeout(STEP)
        .build()
        .unwrap()
        .post(format!("http://{}/v1/plan", server.rest_addr))
        .json(&json_request("shadow", 1))
        .send()
        .await;
    assert!(
        plain.is_err(),
        "plain HTTP against the HTTPS port: {plain:?}"
    );

    // The server is still fine after the failed handshakes.
    assert_eq!(rest_plan(&client, &server).await.unwrap(), 200);
    assert!(
        grpc_plan(grpc_tls(&server, Some(&pki.ca), None))
            .await
            .is_ok()
    );
}

/// A WebSocket to `/v1/stabilize` over a rustls stream that trusts `ca`.
async fn wss(
    server: &Server,
    ca: &str,
) -> tokio_tungstenite::WebSocketStream<tokio_rustls::client::TlsStream<tokio::net::TcpStream>> {
    let mut roots = rustls::RootCertStore::empty();
    for cert in rustls::pki_types::CertificateDer::pem_slice_iter(ca.as_bytes()) {
        roots.add(cert.unwrap()).unwrap();
    }
    let config = rustls::ClientConfig::builder_with_provider(Arc::new(
        rustls::crypto::ring::default_provider(),
    ))
    .with_safe_default_protocol_versions()
    .unwrap()
    .with_root_certificates(roots)
    .with_no_client_auth();
    let tcp = tokio::net::TcpStream::connect(server.rest_addr)
        .await
        .unwrap();
    let name = rustls::pki_types::ServerName::try_from("127.0.0.1").unwrap();
    let tls = tokio_rustls::TlsConnector::from(Arc::new(config))
        .connect(name, tcp)
        .await
        .expect("TLS handshake");
    let url = format!("wss://{}/v1/stabilize", server.rest_addr);
    tokio::time::timeout(STEP, tokio_tungstenite::client_async(url, tls))
        .await
        .unwrap()
        .expect("WebSocket handshake over TLS")
        .0
}

/// The call failed, refused at the handshake. TLS 1.3 clients finish their side first, so the
/// server's alert (`alert`, rustls's name of it) or only the closed connection may come back.
fn assert_alert<T: std::fmt::Debug, E: std::fmt::Debug>(result: &Result<T, E>, alert: &str) {
    match result {
        Ok(answer) => panic!("refused expected ({alert}), got {answer:?}"),
        Err(e) => {
            let e = format!("{e:?}");
            assert!(
                !e.contains("lert") || e.contains(alert),
                "{alert} expected: {e}"
            );
        }
    }
}

#[tokio::test]
async fn mutual_tls_needs_a_client_certificate_from_the_ca() {
    let pki = Pki::new("mutual");
    let ca_path = pki.path("ca.pem");
    let server = pki.start(&["--tls-client-ca", &ca_path]);

    // No client certificate, or one from another CA: refused on both ports.
    let refused = grpc_plan(grpc_tls(&server, Some(&pki.ca), None)).await;
    assert_alert(&refused, "CertificateRequired");
    let refused = grpc_plan(grpc_tls(&server, Some(&pki.ca), Some(&pki.rogue_client))).await;
    assert_alert(&refused, "UnknownCA");
    let refused = rest_plan(&https(Some(&pki.ca), None), &server).await;
    assert_alert(&refused, "CertificateRequired");
    let refused = rest_plan(&https(Some(&pki.ca), Some(&pki.rogue_client)), &server).await;
    assert_alert(&refused, "UnknownCA");

    // A certificate signed by the CA: plans on both.
    let planned = grpc_plan(grpc_tls(&server, Some(&pki.ca), Some(&pki.client))).await;
    assert!(
        planned.is_ok_and(|hand| hand == "shadow"),
        "gRPC with a client certificate"
    );
    let client = https(Some(&pki.ca), Some(&pki.client));
    assert_eq!(rest_plan(&client, &server).await.unwrap(), 200);
}

/// Runs graspd with `args` (and `--print-config` when asked) and returns (exit code, stderr,
/// stdout); the start must fail before listening.
fn run(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(binary("graspd", "GRASPD_BIN"))
        .env_remove("GRASPD_CONFIG")
        .env_remove("GRASPD_TLS_CERT")
        .env_remove("GRASPD_TLS_KEY")
        .env_remove("GRASPD_TLS_CLIENT_CA")
        .env("GRASPD_LOG", "warn")
        .args(["--grpc-addr", "127.0.0.1:0", "--rest-addr", "127.0.0.1:0"])
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

fn assert_refused(args: &[&str], flag: &str, file: &Path) {
    let (code, err, out) = run(args);
    assert!(
        !out.contains("graspd listening"),
        "{args:?} started:\n{out}\n{err}"
    );
    assert!(matches!(code, Some(c) if c != 0), "{args:?}: exit {code:?}");
    let file = file.to_str().unwrap();
    assert!(
        err.contains(flag) && err.contains(file),
        "{args:?}: the message should name {flag} and {file}:\n{err}"
    );
    assert!(!err.contains("PRIVATE KEY"), "a key in the message:\n{err}");
}

#[test]
fn bad_tls_files_stop_the_start_naming_the_flag_and_the_file() {
    let pki = Pki::new("bad");
    let (cert, key) = (pki.path("server.pem"), pki.path("server.key"));
    let (missing, garbage) = (pki.path("missing.pem"), pki.path("garbage.pem"));
    let (other_key, ca) = (pki.path("other.key"), pki.path("ca.pem"));
    let p = |s: &String| PathBuf::from(s);

    assert_refused(
        &["--tls-cert", &missing, "--tls-key", &key],
        "--tls-cert",
        &p(&missing),
    );
    assert_refused(
        &["--tls-cert", &garbage, "--tls-key", &key],
        "--tls-cert",
        &p(&garbage),
    );
    assert_refused(
        &["--tls-cert", &cert, "--tls-key", &missing],
        "--tls-key",
        &p(&missing),
    );
    assert_refused(
        &["--tls-cert", &cert, "--tls-key", &garbage],
        "--tls-key",
        &p(&garbage),
    );
    // A key that does not match the certificate.
    assert_refused(
        &["--tls-cert", &cert, "--tls-key", &other_key],
        "--tls-key",
        &p(&other_key),
    );
    assert_refused(
        &[
            "--tls-cert",
            &cert,
            "--tls-key",
            &key,
            "--tls-client-ca",
            &garbage,
        ],
        "--tls-client-ca",
        &p(&garbage),
    );
    // Only one of the pair, or a client CA without TLS.
    assert_refused(&["--tls-cert", &cert], "--tls-key", &p(&cert));
    assert_refused(&["--tls-key", &key], "--tls-cert", &p(&key));
    let (code, err, _) = run(&["--tls-client-ca", &ca]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--tls-client-ca"), "{err}");

    // --print-config shows the paths, never the key.
    let (code, err, out) = run(&["--tls-cert", &cert, "--tls-key", &key, "--print-config"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains(&key) && out.contains(&cert), "{out}");
    assert!(!out.contains("PRIVATE KEY"), "{out}");
}

/// Replaces the server's certificate and key with ones signed by a new CA (as cert-manager
/// renews them: the files rewritten in place); returns the new CA.
fn renew(pki: &Pki) -> String {
    let authority = ca("renewed CA");
    let server = leaf(
        &authority,
        &["localhost", "127.0.0.1"],
        ExtendedKeyUsagePurpose::ServerAuth,
    );
    std::fs::write(pki.dir.join("server.key"), server.key).unwrap();
    std::fs::write(pki.dir.join("server.pem"), server.cert).unwrap();
    authority.pem()
}

/// Waits until new HTTPS connections trusting `ca` are served (or STEP passes).
async fn served_with(server: &Server, ca: &str) -> bool {
    let started = std::time::Instant::now();
    while started.elapsed() < STEP {
        // A fresh client: a new connection, a new handshake.
        if rest_plan(&https(Some(ca), None), server).await.is_ok() {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    false
}

/// Certificates are reloaded without a restart (issue 20): on SIGHUP and when the files change.
/// New handshakes on both ports present the new certificate; a connection opened before keeps
/// working; files that fail the checks leave the server on the certificate it had.
#[tokio::test]
async fn certificates_reload_on_sighup_and_on_file_change_without_dropping_connections() {
    let pki = Pki::new("reload");
    let server = pki.start(&[]);
    // A gRPC connection made with the first certificate, and used once.
    let mut before = grpc_tls(&server, Some(&pki.ca), None);
    assert!(grpc_plan(before.clone()).await.is_ok());

    // Bad files (a key that does not match): nothing changes.
    std::fs::copy(pki.dir.join("other.key"), pki.dir.join("server.key")).unwrap();
    let hup = |pid: u32| {
        let status = Command::new("kill")
            .args(["-HUP", &pid.to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    };
    hup(server.pid());
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert_eq!(
        rest_plan(&https(Some(&pki.ca), None), &server)
            .await
            .unwrap(),
        200
    );

    // Renewed files and SIGHUP: new connections need the new CA, on both ports.
    let renewed = renew(&pki);
    hup(server.pid());
    assert!(
        served_with(&server, &renewed).await,
        "not reloaded on SIGHUP"
    );
    assert!(
        rest_plan(&https(Some(&pki.ca), None), &server)
            .await
            .is_err()
    );
    assert!(
        grpc_plan(grpc_tls(&server, Some(&renewed), None))
            .await
            .is_ok()
    );
    assert!(
        grpc_plan(grpc_tls(&server, Some(&pki.ca), None))
            .await
            .is_err()
    );
    // The connection opened before the reload still plans.
    let hand = before.plan_grasp(grpc_request("shadow", 2)).await.unwrap();
    assert_eq!(hand.into_inner().hand, "shadow");

    // Renewed again, no signal: the file watch picks it up.
    let again = renew(&pki);
    assert!(
        served_with(&server, &again).await,
        "not reloaded on file change"
    );
    assert!(
        rest_plan(&https(Some(&renewed), None), &server)
            .await
            .is_err()
    );
}

/// `graspd --probe` with the server's own configuration: 0 while it is ready, 1 once it is gone.
fn probe(args: &[&str]) -> bool {
    Command::new(binary("graspd", "GRASPD_BIN"))
        .arg("--probe")
        .args(args)
        .env_remove("GRASPD_CONFIG")
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap()
        .success()
}

/// Probes with TLS on (issue 20): the container HEALTHCHECK (`graspd --probe`) speaks the REST
/// port's TLS; with mutual TLS, which no probe can pass, the plain-HTTP probe port
/// (`--probe-addr`) answers /healthz and /readyz only.
#[tokio::test]
async fn probes_work_with_tls_and_with_mutual_tls_through_the_probe_port() {
    let pki = Pki::new("probe");
    let (cert, key, ca) = (
        pki.path("server.pem"),
        pki.path("server.key"),
        pki.path("ca.pem"),
    );
    let server = pki.start(&[]);
    let rest = server.rest_addr.to_string();
    let tls_args = ["--tls-cert", cert.as_str(), "--tls-key", key.as_str()];
    let with = |extra: &[&str]| -> Vec<String> {
        tls_args
            .iter()
            .chain(extra)
            .map(|s| s.to_string())
            .collect()
    };
    let args = with(&["--rest-addr", &rest]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    assert!(probe(&args), "HEALTHCHECK over TLS");
    assert!(!probe(&["--rest-addr", &rest]), "plain HTTP to a TLS port");
    drop(server);
    assert!(!probe(&args), "the probe passes with graspd stopped");

    let server = pki.start(&["--tls-client-ca", &ca, "--probe-addr", "127.0.0.1:0"]);
    let probe_addr = server
        .probe_addr
        .expect("probe= in the listening line")
        .to_string();
    let plain = reqwest::Client::new();
    for (path, status) in [
        ("/readyz", 200),
        ("/healthz", 200),
        ("/v1/hands", 404),
        ("/metrics", 404),
    ] {
        let response = plain
            .get(format!("http://{probe_addr}{path}"))
            .send()
            .await
            .unwrap();
        assert_eq!(response.status().as_u16(), status, "{path}");
    }
    let rest = server.rest_addr.to_string();
    let mutual = with(&["--tls-client-ca", &ca, "--rest-addr", &rest]);
    let mut mutual: Vec<&str> = mutual.iter().map(String::as_str).collect();
    assert!(
        !probe(&mutual),
        "no client certificate, no answer on the REST port"
    );
    mutual.extend(["--probe-addr", &probe_addr]);
    assert!(probe(&mutual), "HEALTHCHECK through the probe port");
}
