//! Answers decided before the body is read still reach HTTP/1.1 clients (issue 20). A client
//! that writes its whole body before reading — curl, most HTTP libraries — gets EPIPE instead of
//! the status when the server answers early (a missing token, a deadline already passed, a wrong
//! content type) and closes the connection with the body half sent. This layer, outside the
//! edge, keeps the request body where it can reach it after the answer is made and reads what
//! is left of it (at most `max_message_bytes`, within [`DRAIN_TIMEOUT`]) before answering; a body
//! declared larger than the limit is not drained (its 413 closes the connection, as before).

use axum::body::Body;
use http::{Request, Response, header::CONTENT_LENGTH};
use http_body::{Frame, SizeHint};
use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::Duration;
use tower::{Layer, Service};

/// The longest an answer waits for the rest of a body it does not need.
pub const DRAIN_TIMEOUT: Duration = Duration::from_secs(10);

/// The request body, shared by the handler (through [`Borrowed`]) and the layer.
type Slot = Arc<Mutex<Option<Body>>>;

#[derive(Debug, Clone, Copy)]
pub struct DrainLayer {
    limit: usize,
}

impl DrainLayer {
    /// Drains at most `limit` bytes (`max_message_bytes`).
    pub fn new(limit: usize) -> Self {
        Self { limit }
    }
}

impl<S> Layer<S> for DrainLayer {
    type Service = Drain<S>;

    fn layer(&self, inner: S) -> Drain<S> {
        Drain {
            inner,
            limit: self.limit,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Drain<S> {
    inner: S,
    limit: usize,
}

impl<S, B> Service<Request<Body>> for Drain<S>
where
    S: Service<Request<Body>, Response = Response<B>> + Clone + Send + 'static,
    S::Future: Send + 'static,
    B: Send + 'static,
{
    type Response = Response<B>;
    type Error = S::Error;
    type Future = Pin<Box<dyn Future<Output = Result<Response<B>, S::Error>> + Send>>;

    fn poll_ready(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), Self::Error>> {
        self.inner.poll_ready(cx)
    }

    fn call(&mut self, request: Request<Body>) -> Self::Future {
        let (parts, body) = request.into_parts();
        let declared = parts
            .headers
            .get(CONTENT_LENGTH)
            .and_then(|v| v.to_str().ok()?.parse::<u64>().ok());
        let limit = self.limit;
        let slot: Slot = Arc::new(Mutex::new(Some(body)));
        let request = Request::from_parts(parts, Body::new(Borrowed(slot.clone())));
        let future = self.inner.call(request);
        Box::pin(async move {
            let response = future.await?;
            if declared.is_none_or(|n| n <= limit as u64) {
                drain(&slot, limit).await;
            }
            Ok(response)
        })
    }
}

/// Reads and drops what is left of the body: at most `limit` bytes, within [`DRAIN_TIMEOUT`].
async fn drain(slot: &Slot, limit: usize) {
    use tokio_stream::StreamExt;
    let Some(body) = slot.lock().unwrap_or_else(|e| e.into_inner()).take() else {
        return;
    };
    if http_body::Body::is_end_stream(&body) {
        return;
    }
    let mut data = body.into_data_stream();
    let _ = tokio::time::timeout(DRAIN_TIMEOUT, async {
        let mut seen = 0usize;
        while let Some(Ok(chunk)) = data.next().await {
            seen += chunk.len();
            if seen > limit {
                break;
            }
        }
    })
    .await;
}

/// The handler's view of the shared body.
struct Borrowed(Slot);

impl http_body::Body for Borrowed {
    type Data = bytes::Bytes;
    type Error = axum::Error;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Self::Data>, Self::Error>>> {
        let mut body = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match body.as_mut() {
            Some(b) => Pin::new(b).poll_frame(cx),
            None => Poll::Ready(None),
        }
    }

    fn is_end_stream(&self) -> bool {
        let body = self.0.lock().unwrap_or_else(|e| e.into_inner());
        body.as_ref().is_none_or(http_body::Body::is_end_stream)
    }

    fn size_hint(&self) -> SizeHint {
        let body = self.0.lock().unwrap_or_else(|e| e.into_inner());
        body.as_ref()
            .map_or_else(|| SizeHint::with_exact(0), http_body::Body::size_hint)
    }
}
