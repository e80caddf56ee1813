//! Tactile requests at the edge: `POST /v1/tactile/analyze` JSON (selector even) or a protobuf
//! `StabilizeRequest` session followed by frames (selector odd, length-delimited messages),
//! opened and stepped through the facade exactly as the transports do.
#![no_main]
use graspd::facade::{GraspService, Limits};
use graspd_api::convert;
use graspd_api::json::{self, AnalyzeRequestJson};
use graspd_core::hand::HandCatalog;
use graspd_proto::v1 as pb;
use libfuzzer_sys::fuzz_target;
use prost::Message;
use std::sync::OnceLock;

fn service() -> &'static GraspService {
    static S: OnceLock<GraspService> = OnceLock::new();
    S.get_or_init(|| GraspService::new(HandCatalog::builtin(), Limits::default()))
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, mut rest)) = data.split_first() else {
        return;
    };
    if selector % 2 == 0 {
        if let Ok(body) = json::parse::<AnalyzeRequestJson>(rest, "body") {
            let session = json::tactile_session_from_json(body.session);
            let frames: Vec<_> = body
                .frames
                .into_iter()
                .map(json::tactile_frame_from_json)
                .collect();
            let _ = service().analyze_tactile(session, &frames);
        }
        return;
    }
    let Ok(first) = pb::StabilizeRequest::decode_length_delimited(&mut rest) else {
        return;
    };
    let Ok(request) = convert::stabilize_session_from_proto(first) else {
        return;
    };
    let Ok(mut session) = service().open_tactile_session(request) else {
        return;
    };
    while let Ok(m) = pb::StabilizeRequest::decode_length_delimited(&mut rest) {
        let Ok(frame) = convert::stabilize_frame_from_proto(m) else {
            return;
        };
        if session.step(&frame).is_err() {
            return;
        }
    }
});
