//! ROS payloads against the real binary (issue 20): a `sensor_msgs/PointCloud2` in any layout a
//! driver writes (organised or not, either endianness, padded points and rows, NaN pixels) plans
//! exactly like the packed-float cloud of the same points over gRPC and REST; bad layouts are
//! refused naming the field, and the next request works; `output.moveit_grasps` returns each
//! ranked candidate in the layout of `moveit_msgs/Grasp`, the same over both transports.

use graspd_api::convert::cloud2_to_proto;
use graspd_core::cloud::PointCloud;
use graspd_e2e::{
    Server, assert_valid_plan_works, base64, cylinder, grpc_request, http, json_request,
    rest_error, table_plane, without_timings,
};
use graspd_proto::v1 as pb;
use nalgebra::Point3;
use pb::plan_grasp_request::Input;

/// A response with its wall-clock fields cleared, to compare two plans.
fn plan_only(mut r: pb::PlanGraspResponse) -> pb::PlanGraspResponse {
    r.timings = None;
    for s in [&mut r.stage1, &mut r.stage2].into_iter().flatten() {
        s.seconds = 0.0;
    }
    r
}

/// The cylinder as an organised `rows × cols` PointCloud2 the way a depth camera's driver writes
/// one: big-endian float64 x, y, z after an `rgb` field, 4 bytes of padding per point and 16
/// per row, every fifth cell an invalid (NaN) pixel, `is_dense = false`.
fn organised_cloud2(points: &[Point3<f64>], cols: u32) -> pb::PointCloud2 {
    let point_step = 4 + 24 + 4;
    let cells = points.len() + points.len() / 4 + 1;
    let rows = (cells as u32).div_ceil(cols);
    let row_step = cols * point_step + 16;
    let mut data = Vec::new();
    let mut next = points.iter();
    for r in 0..rows {
        for c in 0..cols {
            data.extend_from_slice(&0x00ff8800u32.to_be_bytes());
            let p = if (r * cols + c) % 5 == 4 {
                None
            } else {
                next.next()
            };
            let v = p.map_or([f64::NAN; 3], |p| [p.x, p.y, p.z]);
            for x in v {
                data.extend_from_slice(&x.to_be_bytes());
            }
            data.extend_from_slice(&[0; 4]);
        }
        data.extend_from_slice(&[0; 16]);
    }
    assert!(next.next().is_none(), "the grid holds every point");
    let field = |name: &str, offset: u32, datatype: u32| pb::PointField {
        name: name.into(),
        offset,
        datatype,
        count: 1,
    };
    pb::PointCloud2 {
        height: rows,
        width: cols,
        fields: vec![
            field("rgb", 0, 6),
            field("x", 4, 8),
            field("y", 12, 8),
            field("z", 20, 8),
        ],
        is_bigendian: true,
        point_step,
        row_step,
        data,
        is_dense: false,
        frame_id: "camera_depth_optical_frame".into(),
    }
}

fn with_cloud2(c: pb::PointCloud2) -> pb::PlanGraspRequest {
    let mut r = grpc_request("shadow", 3);
    r.input = Some(Input::Cloud2(c));
    r
}

/// The cloud2 of a request as rosbridge would write it in JSON.
fn cloud2_json(c: &pb::PointCloud2) -> serde_json::Value {
    let fields: Vec<serde_json::Value> = c
        .fields
        .iter()
        .map(|f| {
            serde_json::json!({"name": f.name, "offset": f.offset, "datatype": f.datatype,
                               "count": f.count})
        })
        .collect();
    serde_json::json!({
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": c.frame_id},
        "height": c.height, "width": c.width, "fields": fields,
        "is_bigendian": c.is_bigendian, "point_step": c.point_step, "row_step": c.row_step,
        "data": base64(&c.data), "is_dense": c.is_dense,
    })
}

/// [`json_request`] with the cloud given as `cloud2` instead.
fn json_with_cloud2(hand: &str, seed: u64, cloud: &pb::PointCloud2) -> serde_json::Value {
    let mut body = json_request(hand, seed);
    let o = body.as_object_mut().unwrap();
    o.remove("cloud");
    o.insert("cloud2".into(), cloud2_json(cloud));
    body
}

async fn rest_plan(server: &Server, body: &serde_json::Value) -> serde_json::Value {
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(body)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    response.json().await.unwrap()
}

#[tokio::test]
async fn pointcloud2_layouts_plan_like_the_packed_cloud() {
    let server = Server::start();
    let mut grpc = server.grpc().await;
    let points = cylinder(2000);
    let packed = plan_only(
        grpc.plan_grasp(grpc_request("shadow", 3))
            .await
            .unwrap()
            .into_inner(),
    );
    let unorganised = cloud2_to_proto(
        &PointCloud {
            points: points.clone(),
            normals: None,
        },
        "world",
    );
    for (what, c) in [
        ("unorganised little-endian float32", unorganised.clone()),
        (
            "organised big-endian float64, padded, NaN pixels",
            organised_cloud2(&points, 48),
        ),
    ] {
        let plan = grpc.plan_grasp(with_cloud2(c)).await.unwrap().into_inner();
        assert_eq!(plan_only(plan), packed, "{what}");
    }

    // REST: base64 data, and data as an array of byte values.
    let reference = without_timings(rest_plan(&server, &json_request("shadow", 3)).await);
    let mut body = json_with_cloud2("shadow", 3, &organised_cloud2(&points, 48));
    assert_eq!(without_timings(rest_plan(&server, &body).await), reference);
    let mut array = cloud2_json(&unorganised);
    array["data"] = serde_json::json!(unorganised.data);
    body["cloud2"] = array;
    assert_eq!(without_timings(rest_plan(&server, &body).await), reference);
}

#[tokio::test]
async fn bad_pointcloud2_layouts_are_refused_naming_the_field() {
    let server = Server::start_with(&["--max-points", "3000"]);
    let mut grpc = server.grpc().await;
    let good = cloud2_to_proto(
        &PointCloud {
            points: cylinder(500),
            normals: None,
        },
        "world",
    );
    let mut no_z = good.clone();
    no_z.fields.retain(|f| f.name != "z");
    let mut short_step = good.clone();
    short_step.point_step = 8;
    let mut lying_rows = good.clone();
    lying_rows.height = 2;
    let mut huge = good.clone();
    huge.width = 100_000;
    huge.height = 100_000;
    let cases = [
        (no_z, "cloud2.fields", 400, tonic::Code::InvalidArgument),
        (
            short_step,
            "cloud2.point_step",
            400,
            tonic::Code::InvalidArgument,
        ),
        (lying_rows, "cloud2.data", 400, tonic::Code::InvalidArgument),
        (huge, "cloud2.width", 413, tonic::Code::ResourceExhausted),
    ];
    for (cloud, field, http_status, code) in cases {
        let status = grpc
            .plan_grasp(with_cloud2(cloud.clone()))
            .await
            .unwrap_err();
        assert_eq!(status.code(), code, "{field}: {status:?}");
        assert!(status.message().contains(field), "{field}: {status:?}");

        let body = json_with_cloud2("shadow", 1, &cloud);
        let response = http()
            .post(server.rest_url("/v1/plan"))
            .json(&body)
            .send()
            .await
            .unwrap();
        let (status, _, f, message) = rest_error(response).await;
        assert_eq!(
            (status, f.as_deref()),
            (http_status, Some(field)),
            "{message}"
        );
    }
    // Both a cloud and a cloud2: refused, not one of them silently used.
    let mut body = json_request("shadow", 1);
    body["cloud2"] = cloud2_json(&good);
    let response = http()
        .post(server.rest_url("/v1/plan"))
        .json(&body)
        .send()
        .await
        .unwrap();
    let (status, _, field, _) = rest_error(response).await;
    assert_eq!((status, field.as_deref()), (400, Some("cloud2")));
    assert_valid_plan_works(&server).await;
}

fn v3(v: &Option<pb::Vec3>) -> [f64; 3] {
    let v = v.as_ref().unwrap();
    [v.x, v.y, v.z]
}

fn joint_values(j: &[pb::JointAngle]) -> (Vec<String>, Vec<f64>) {
    (
        j.iter().map(|a| a.name.clone()).collect(),
        j.iter().map(|a| a.angle).collect(),
    )
}

#[tokio::test]
async fn moveit_grasps_carry_each_ranked_candidate() {
    let model = graspd_testkit::testdata_dir().join("hands/robotiq_2f85/2f85.xml");
    let server = Server::start_with(&[
        "--import-hand",
        &format!("robotiq_2f85={}", model.display()),
    ]);
    let mut grpc = server.grpc().await;
    let mut request = with_cloud2(organised_cloud2(&cylinder(2000), 48));
    request.hand = Some(pb::plan_grasp_request::Hand::HandName(
        "robotiq_2f85".into(),
    ));
    request.options.as_mut().unwrap().candidates = Some(3);
    request.hints.as_mut().unwrap().support_plane = Some(table_plane());
    let plain = grpc.plan_grasp(request.clone()).await.unwrap().into_inner();
    assert!(plain.moveit_grasps.is_empty(), "only when asked for");

    request.output = Some(pb::OutputOptions {
        moveit_grasps: true,
        ..Default::default()
    });
    let plan = grpc.plan_grasp(request.clone()).await.unwrap().into_inner();
    assert!(plan.candidates.len() >= 2, "{}", plan.candidates.len());
    assert_eq!(plan.moveit_grasps.len(), plan.candidates.len());
    let frame = "camera_depth_optical_frame";
    for (rank, (g, c)) in plan.moveit_grasps.iter().zip(&plan.candidates).enumerate() {
        assert_eq!(g.id, format!("graspd-{}-{rank}", plan.seed));
        let pose = g.grasp_pose.as_ref().unwrap();
        assert_eq!(pose.header.as_ref().unwrap().frame_id, frame);
        assert_eq!(pose.pose, c.root_pose, "the hand's root link goes there");
        assert_eq!(g.grasp_quality, c.quality.as_ref().unwrap().robustness);

        let pre = g.pre_grasp_posture.as_ref().unwrap();
        let (names, opening) = joint_values(&c.pregrasp_joints);
        assert_eq!(pre.joint_names, names);
        assert_eq!(pre.points.len(), 1);
        assert_eq!(pre.points[0].positions, opening);
        let close = g.grasp_posture.as_ref().unwrap();
        assert_eq!(close.joint_names, names);
        let times: Vec<(i32, u32)> = close
            .points
            .iter()
            .map(|p| {
                let d = p.time_from_start.unwrap();
                (d.sec, d.nanosec)
            })
            .collect();
        assert_eq!(times, [(1, 0), (1, 500_000_000)]);
        assert_eq!(close.points[0].positions, joint_values(&c.joints).1);
        assert_eq!(close.points[1].positions, joint_values(&c.squeeze_joints).1);

        let approach = g.pre_grasp_approach.as_ref().unwrap();
        let direction = approach.direction.as_ref().unwrap();
        assert_eq!(direction.header.as_ref().unwrap().frame_id, frame);
        assert_eq!(v3(&direction.vector), v3(&c.approach));
        let hand = v3(&c.hand_pose.as_ref().unwrap().position);
        let pregrasp = v3(&c.pregrasp_pose.as_ref().unwrap().position);
        let distance = (0..3)
            .map(|k| (hand[k] - pregrasp[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((approach.desired_distance - distance).abs() < 1e-12);
        assert!((approach.min_distance - 0.5 * distance).abs() < 1e-12);
        // Lifted away from the table the plan stood on.
        let retreat = g.post_grasp_retreat.as_ref().unwrap();
        assert_eq!(
            v3(&retreat.direction.as_ref().unwrap().vector),
            [0.0, 0.0, 1.0]
        );
        assert!((retreat.desired_distance - 0.1).abs() < 1e-12);
    }

    // REST: the same grasps in ROS 2's JSON nesting; `output.frame_id` names the frame.
    let mut body = json_with_cloud2("robotiq_2f85", 3, &organised_cloud2(&cylinder(2000), 48));
    body["options"]["candidates"] = serde_json::json!(3);
    body["output"] = serde_json::json!({"moveit_grasps": true, "frame_id": "table"});
    let json = rest_plan(&server, &body).await;
    let grasps = json["moveit_grasps"].as_array().unwrap();
    assert_eq!(grasps.len(), plan.moveit_grasps.len());
    for (j, g) in grasps.iter().zip(&plan.moveit_grasps) {
        assert_eq!(j["id"], g.id.as_str());
        assert_eq!(j["grasp_pose"]["header"]["frame_id"], "table");
        let p = g.grasp_pose.as_ref().unwrap().pose.as_ref().unwrap();
        assert_eq!(
            j["grasp_pose"]["pose"]["orientation"]["w"],
            p.orientation.as_ref().unwrap().w
        );
        assert_eq!(
            j["pre_grasp_approach"]["direction"]["vector"]["z"],
            g.pre_grasp_approach
                .as_ref()
                .unwrap()
                .direction
                .as_ref()
                .unwrap()
                .vector
                .as_ref()
                .unwrap()
                .z
        );
        assert_eq!(
            j["grasp_posture"]["points"][1]["time_from_start"]["nanosec"],
            500_000_000
        );
        assert_eq!(
            j["pre_grasp_posture"]["joint_names"],
            serde_json::json!(g.pre_grasp_posture.as_ref().unwrap().joint_names)
        );
    }
}
