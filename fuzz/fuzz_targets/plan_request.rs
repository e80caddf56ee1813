//! `PlanGrasp` / `POST /v1/plan` decoding at the edge: the first byte picks protobuf or JSON;
//! the message is converted to the domain request under small limits.
#![no_main]
use graspd_api::Limits;
use graspd_api::convert::plan_request_from_proto;
use graspd_api::json::{self, PlanRequestJson, plan_request_from_json};
use graspd_proto::v1 as pb;
use libfuzzer_sys::fuzz_target;
use prost::Message;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let limits = Limits {
        max_points: 4096,
        ..Limits::default()
    };
    if selector % 2 == 0 {
        if let Ok(request) = pb::PlanGraspRequest::decode(rest) {
            let _ = plan_request_from_proto(request, &limits);
        }
    } else if let Ok(request) = json::parse::<PlanRequestJson>(rest, "body") {
        let _ = plan_request_from_json(request, None, Default::default(), &limits);
    }
});
