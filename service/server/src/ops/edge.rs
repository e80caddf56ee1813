//! The edge layer: one tower layer, used by both transports, that gives every request
//!
//! * an id — the caller's `x-request-id` when sane ([`super::sane_request_id`]), else a fresh
//!   one — echoed in the response and carried by a `request` tracing span (field `request_id`)
//!   around the request's handling, so its log lines name it;
//! * bearer-token authentication when tokens are configured (the transport names the routes that
//!   stay open: probes and metrics);
//! * the caller's deadline (gRPC `grpc-timeout`, REST `x-request-timeout-ms`): at the deadline the
//!   handling is dropped and the caller answered DEADLINE_EXCEEDED / 504 (a plan already on a
//!   planner thread finishes there, holding its planner slot);
//! * metrics: in flight, then counted by route and code with its latency when its answer ends
//!   (for streams: when the stream ends).
//!
//! A transport plugs in through [`EdgeHooks`]: how to name a route, which routes are open, how
//! to read a deadline and how to answer a refusal.

use super::{MAX_REQUEST_ID_LEN, Ops, REQUEST_ID_HEADER, RequestId, Transport};
use super::{Metrics, Tokens, new_request_id, sane_request_id};
use bytes::Bytes;
use http::{HeaderMap, HeaderValue, Request, Response};
use http_body::{Body, Frame, SizeHint};
use pin_project_lite::pin_project;
use std::borrow::Cow;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll, ready};
use std::time::Duration;
use tower::{Layer, Service};
use tracing::Instrument;

/// Why the edge answers a request itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// No `authorization: Bearer …` or a token that is not configured.
    Unauthenticated,
    /// The caller's deadline (this long after arrival) passed before the answer.
    DeadlineExceeded(Duration),
    /// A deadline header that cannot be read.
    BadTimeout(String),
}

/// An answer's metrics code (a gRPC code name or an HTTP status) and whether it is an error.
pub type AnswerCode = (Cow<'static, str>, bool);

/// How a transport plugs into the edge layer.
#[derive(Debug, Clone, Copy)]
pub struct EdgeHooks {
    pub transport: Transport,
    /// The route label of a request (bounded: unknown routes share one label).
    pub route: fn(&http::request::Parts) -> Cow<'static, str>,
    /// Routes answered without a token (probes, metrics), by path.
    pub open: fn(&str) -> bool,
    /// The caller's time budget from the request headers, if it gave one.
    pub timeout: fn(&HeaderMap) -> Result<Option<Duration>, String>,
    /// The answer to a refusal (status, headers, body).
    pub refusal: fn(&Refusal) -> Response<Bytes>,
    /// The metrics code of an answer from its headers (REST: the status; gRPC: `grpc-status`
    /// when the answer is trailers-only) and whether it is an error.
    pub code: fn(&http::response::Parts) -> Option<AnswerCode>,
    /// The code of a gRPC answer from its trailers.
    pub trailer_code: fn(&HeaderMap) -> Option<AnswerCode>,
    /// The code of an answer that was abandoned (the caller went away) or broke.
    pub abandoned_code: &'static str,
}

struct Shared {
    hooks: EdgeHooks,
    metrics: Metrics,
    tokens: Arc<Tokens>,
}

/// The layer; see the module documentation.
#[derive(Clone)]
pub struct EdgeLayer {
    shared: Arc<Shared>,
}

impl EdgeLayer {
    pub fn new(hooks: EdgeHooks, ops: &Ops) -> Self {
        Self {
            shared: Arc::new(Shared {
                hooks,
                metrics: ops.metrics.clone(),
                tokens: ops.tokens.clone(),
            }),
        }
    }
}

impl<S> Layer<S> for EdgeLayer {
    type Service = EdgeService<S>;

    fn layer(&self, inner: S) -> EdgeService<S> {
        EdgeService {
            inner,
            shared: self.shared.clone(),
        }
    }
}

#[derive(Clone)]
pub struct EdgeService<S> {
    inner: S,
    shared: Arc<Shared>,
}

type BoxFuture<T> = Pin<Box<dyn Future<Output = T> + Send>>;

impl<S, ReqB, ResB> Service<Request<ReqB>> for EdgeService<S>
where
    S: Service<Request<ReqB>, Response = Response<ResB>> + Clone + Send + 'static,
    S::Future: Send + 'static,
    S::Error: Send + 'static,
    ReqB: Send + 'static,
    ResB: Body<Data = Bytes> + Send + 'static,
{
    type Response = Response<EdgeBody<ResB>>;
    type Error = S::Error;
    type Future = BoxFuture<Result<Self::Response, S::Error>>;

    fn poll_ready(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), Self::Error>> {
        self.inner.poll_ready(cx)
    }

    fn call(&mut self, request: Request<ReqB>) -> Self::Future {
        let arrived = tokio::time::Instant::now();
        let shared = self.shared.clone();
        let hooks = shared.hooks;
        let (mut parts, body) = request.into_parts();

        let id: Arc<str> = match parts
            .headers
            .get(REQUEST_ID_HEADER)
            .and_then(|v| sane_request_id(v.as_bytes()))
        {
            Some(id) => id.into(),
            None => new_request_id().into(),
        };
        debug_assert!(id.len() <= MAX_REQUEST_ID_LEN);
        let id_header = HeaderValue::from_str(&id).expect("request ids are visible ASCII");
        parts.headers.insert(REQUEST_ID_HEADER, id_header.clone());
        parts.extensions.insert(RequestId(id.clone()));
        let route = (hooks.route)(&parts);
        let span = tracing::info_span!(
            "request",
            request_id = %id,
            transport = hooks.transport.name(),
            route = %route,
        );
        shared.metrics.request_started(hooks.transport);
        let observer = Observer {
            metrics: shared.metrics.clone(),
            transport: hooks.transport,
            route,
            arrived,
            code: None,
            span: span.clone(),
            abandoned_code: hooks.abandoned_code,
        };
        let respond = move |refusal: Refusal, mut observer: Observer| {
            let response = (hooks.refusal)(&refusal);
            let (mut parts, bytes) = response.into_parts();
            parts.headers.insert(REQUEST_ID_HEADER, id_header.clone());
            observer.code = (hooks.code)(&parts);
            Response::from_parts(parts, EdgeBody::fixed(bytes, observer))
        };

        if !shared.tokens.is_empty()
            && !(hooks.open)(parts.uri.path())
            && !shared.tokens.accepts(
                parts
                    .headers
                    .get(http::header::AUTHORIZATION)
                    .map(HeaderValue::as_bytes),
            )
        {
            shared.metrics.unauthenticated(hooks.transport);
            span.in_scope(|| tracing::debug!("refused: missing or wrong bearer token"));
            return Box::pin(std::future::ready(Ok(respond(
                Refusal::Unauthenticated,
                observer,
            ))));
        }
        let timeout = match (hooks.timeout)(&parts.headers) {
            Ok(t) => t,
            Err(message) => {
                return Box::pin(std::future::ready(Ok(respond(
                    Refusal::BadTimeout(message),
                    observer,
                ))));
            }
        };
        let deadline = timeout.and_then(|t| arrived.checked_add(t).map(|d| (d, t)));

        let clone = self.inner.clone();
        let mut inner = std::mem::replace(&mut self.inner, clone);
        let future = {
            let _entered = span.enter();
            inner.call(Request::from_parts(parts, body))
        }
        .instrument(span.clone());
        Box::pin(async move {
            let mut observer = observer;
            let result = match deadline {
                None => future.await,
                Some((deadline, timeout)) => {
                    match tokio::time::timeout_at(deadline, future).await {
                        Ok(result) => result,
                        Err(_) => {
                            span.in_scope(|| {
                                tracing::debug!(
                                    timeout_ms = timeout.as_millis() as u64,
                                    "deadline exceeded"
                                )
                            });
                            return Ok(respond(Refusal::DeadlineExceeded(timeout), observer));
                        }
                    }
                }
            };
            let response = result?;
            let (mut parts, body) = response.into_parts();
            parts.headers.insert(
                REQUEST_ID_HEADER,
                HeaderValue::from_str(&id).expect("ASCII"),
            );
            observer.code = (hooks.code)(&parts);
            Ok(Response::from_parts(
                parts,
                EdgeBody::wrap(body, observer, hooks.trailer_code),
            ))
        })
    }
}

/// Records a request when dropped: with the answer's body, or with the request's future when it
/// is abandoned.
struct Observer {
    metrics: Metrics,
    transport: Transport,
    route: Cow<'static, str>,
    arrived: tokio::time::Instant,
    /// The answer's code, once known (headers or trailers).
    code: Option<AnswerCode>,
    span: tracing::Span,
    abandoned_code: &'static str,
}

impl Drop for Observer {
    fn drop(&mut self) {
        let seconds = self.arrived.elapsed().as_secs_f64();
        let (code, error) = self
            .code
            .take()
            .unwrap_or((Cow::Borrowed(self.abandoned_code), true));
        self.span.in_scope(|| {
            tracing::debug!(code = %code, seconds, "request finished");
        });
        self.metrics.request_finished(
            self.transport,
            std::mem::take(&mut self.route),
            code,
            error,
            seconds,
        );
    }
}

pin_project! {
    /// The answer's body: the handler's, or the edge's own fixed one; records the request when it
    /// ends or is dropped.
    pub struct EdgeBody<B> {
        #[pin]
        inner: Option<B>,
        fixed: Option<Bytes>,
        observer: Option<Observer>,
        trailer_code: fn(&HeaderMap) -> Option<AnswerCode>,
    }
}

fn no_trailer_code(_: &HeaderMap) -> Option<AnswerCode> {
    None
}

impl<B> EdgeBody<B> {
    fn wrap(
        inner: B,
        observer: Observer,
        trailer_code: fn(&HeaderMap) -> Option<AnswerCode>,
    ) -> Self {
        Self {
            inner: Some(inner),
            fixed: None,
            observer: Some(observer),
            trailer_code,
        }
    }

    fn fixed(bytes: Bytes, observer: Observer) -> Self {
        Self {
            inner: None,
            fixed: (!bytes.is_empty()).then_some(bytes),
            observer: Some(observer),
            trailer_code: no_trailer_code,
        }
    }
}

impl<B> Default for EdgeBody<B> {
    fn default() -> Self {
        Self {
            inner: None,
            fixed: None,
            observer: None,
            trailer_code: no_trailer_code,
        }
    }
}

impl<B> Body for EdgeBody<B>
where
    B: Body<Data = Bytes>,
{
    type Data = Bytes;
    type Error = B::Error;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, B::Error>>> {
        let this = self.project();
        let Some(inner) = this.inner.as_pin_mut() else {
            let frame = this.fixed.take().map(|b| Ok(Frame::data(b)));
            if frame.is_none() {
                this.observer.take();
            }
            return Poll::Ready(frame);
        };
        let frame = ready!(inner.poll_frame(cx));
        match &frame {
            Some(Ok(f)) => {
                if let (Some(trailers), Some(observer)) = (f.trailers_ref(), this.observer.as_mut())
                    && let Some(code) = (this.trailer_code)(trailers)
                {
                    observer.code = Some(code);
                }
            }
            Some(Err(_)) => {
                if let Some(observer) = this.observer.as_mut() {
                    observer.code = None;
                }
                this.observer.take();
            }
            None => {
                this.observer.take();
            }
        }
        Poll::Ready(frame)
    }

    fn is_end_stream(&self) -> bool {
        match &self.inner {
            Some(b) => b.is_end_stream(),
            None => self.fixed.is_none(),
        }
    }

    fn size_hint(&self) -> SizeHint {
        match &self.inner {
            Some(b) => b.size_hint(),
            None => SizeHint::with_exact(self.fixed.as_ref().map_or(0, |b| b.len() as u64)),
        }
    }
}
