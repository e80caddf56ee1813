"""graspd_client against the real binary on loopback: plans from numpy clouds for every built-in
hand, bad input named by field, RGB-D requests, a tactile session, and stubs in sync with proto/."""

import filecmp
import subprocess
import sys
from pathlib import Path

import grpc
import numpy as np
import pytest

from graspd.v1 import common_pb2, tactile_stabilizer_pb2 as tactile_pb2
from graspd_client import (
    Client,
    Finger,
    Reading,
    cloud_message,
    field_of,
    moveit_grasps_of,
    pointcloud2_from_ros,
    pointcloud2_message,
    points_of,
    rgbd_message,
)

HERE = Path(__file__).resolve().parent


def can(n=2000, radius=0.035, height=0.10, seed=3):
    """A can on the table z = 0 seen from the side and above: its wall toward +x and its lid."""
    rng = np.random.default_rng(seed)
    wall = n * 3 // 4
    theta = rng.uniform(-np.pi / 2, np.pi / 2, wall)
    z = rng.uniform(0.0, height, wall)
    side = np.stack([radius * np.cos(theta), radius * np.sin(theta), z], axis=1)
    r = radius * np.sqrt(rng.uniform(0, 1, n - wall))
    phi = rng.uniform(0, 2 * np.pi, n - wall)
    lid = np.stack([r * np.cos(phi), r * np.sin(phi), np.full(n - wall, height)], axis=1)
    return np.concatenate([side, lid])


TABLE = ((0.0, 0.0, 1.0), 0.0)
VIEW = (0.5, 0.0, 0.4)


def test_cloud_message_round_trips_and_checks_shapes():
    pts = can(100)
    assert np.allclose(points_of(cloud_message(pts)), pts, atol=1e-7)
    with pytest.raises(ValueError, match="points"):
        cloud_message(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="normals"):
        cloud_message(pts, normals=np.zeros((3, 3)))


def test_lists_and_gets_the_built_in_hands(server):
    with Client(server.grpc) as c:
        names = {h.name for h in c.list_hands()}
        assert {"parallel_gripper", "barrett", "shadow"} <= names
        assert len(c.get_hand("shadow").fingers) == 5
        with pytest.raises(grpc.RpcError) as e:
            c.get_hand("nope")
        assert e.value.code() == grpc.StatusCode.NOT_FOUND
        # The built-in hands have no joints, so no posture synergies.
        with pytest.raises(grpc.RpcError) as e:
            c.hand_synergies("shadow")
        assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert field_of(e.value) == "name"
        with pytest.raises(grpc.RpcError) as e:
            c.hand_synergies("nope")
        assert e.value.code() == grpc.StatusCode.NOT_FOUND


@pytest.mark.parametrize(
    "hand,grasp_type,contacts",
    [("parallel_gripper", "pinch", 2), ("barrett", "tripod", 3), ("shadow", "tripod", 3)],
)
def test_plans_on_a_numpy_cloud(server, hand, grasp_type, contacts):
    pts = can()
    with Client(server.grpc) as c:
        plan = c.plan_cloud(pts, hand=hand, seed=1, grasp_type=grasp_type,
                            support_plane=TABLE, viewpoint=VIEW)
    assert plan.hand == hand
    assert plan.grasp_type == common_pb2.GraspType.Value("GRASP_TYPE_" + grasp_type.upper())
    assert len(plan.contacts) == contacts
    for ct in plan.contacts:
        p = np.array([ct.position.x, ct.position.y, ct.position.z])
        if ct.inferred:
            # On the completed, unseen half of the can: near its true wall or lid.
            wall = abs(np.hypot(p[0], p[1]) - 0.035)
            assert p[0] < 0.0 and min(wall, abs(p[2] - 0.10)) < 0.01, p
            continue
        # Seen contacts are cloud points (float32 on the wire).
        assert np.linalg.norm(pts[ct.point_index] - p) < 1e-6
    assert plan.feasible or plan.infeasible_reason
    q = plan.hand_pose.orientation
    assert abs(q.x**2 + q.y**2 + q.z**2 + q.w**2 - 1.0) < 1e-6


def test_the_same_seed_gives_the_same_plan(server):
    pts = can()
    with Client(server.grpc) as c:
        a = c.plan_cloud(pts, hand="barrett", seed=7, support_plane=TABLE)
        b = c.plan_cloud(pts, hand="barrett", seed=7, support_plane=TABLE)
    assert [ct.point_index for ct in a.contacts] == [ct.point_index for ct in b.contacts]
    assert a.hand_pose == b.hand_pose


def test_pointcloud2_plans_like_the_packed_cloud(server):
    pts = can()
    # Organised: 40 columns, every seventh pixel invalid (NaN), as a depth camera's driver writes.
    cells = len(pts) + len(pts) // 6 + 40
    grid = np.full((cells // 40, 40, 3), np.nan)
    flat = grid.reshape(-1, 3)
    valid = [i for i in range(len(flat)) if i % 7 != 6][: len(pts)]
    flat[valid] = pts
    organised = pointcloud2_message(grid, frame_id="camera")
    assert (organised.height, organised.width, organised.is_dense) == (grid.shape[0], 40, False)

    class Ros:  # what rclpy hands over: the same fields, data as a bytes-like array
        def __init__(self, m):
            for name in ("height", "width", "fields", "is_bigendian", "point_step", "row_step",
                         "is_dense"):
                setattr(self, name, getattr(m, name))
            self.data = bytearray(m.data)
            self.header = type("Header", (), {"frame_id": m.frame_id})()

    with Client(server.grpc) as c:
        packed = c.plan_cloud(pts, hand="barrett", seed=4, support_plane=TABLE)
        for cloud in (pointcloud2_message(pts), organised, pointcloud2_from_ros(Ros(organised))):
            plan = c.plan_pointcloud2(cloud, hand="barrett", seed=4, support_plane=TABLE)
            assert [ct.position for ct in plan.contacts] == [ct.position for ct in packed.contacts]
            assert plan.hand_pose == packed.hand_pose
        bad = pointcloud2_message(pts)
        bad.row_step -= 1
        with pytest.raises(grpc.RpcError) as e:
            c.plan_pointcloud2(bad, hand="barrett")
        assert field_of(e.value) == "cloud2.row_step"


def test_moveit_grasps_come_in_the_ros_layout(server):
    with Client(server.grpc) as c:
        plan = c.plan_pointcloud2(pointcloud2_message(can(), frame_id="base_link"), hand="barrett",
                                  seed=2, support_plane=TABLE, moveit_grasps=True, candidates=2)
    grasps = moveit_grasps_of(plan)
    assert len(grasps) == max(1, len(plan.candidates))
    g = grasps[0]
    assert g["id"] == f"graspd-{plan.seed}-0"
    assert g["grasp_pose"]["header"]["frame_id"] == "base_link"
    position = g["grasp_pose"]["pose"]["position"]
    assert [position["x"], position["y"], position["z"]] == pytest.approx(
        [plan.hand_pose.position.x, plan.hand_pose.position.y, plan.hand_pose.position.z])
    approach = g["pre_grasp_approach"]["direction"]["vector"]
    assert [approach["x"], approach["y"], approach["z"]] == pytest.approx(
        [plan.approach.x, plan.approach.y, plan.approach.z])
    assert g["post_grasp_retreat"]["direction"]["vector"] == {"x": 0.0, "y": 0.0, "z": 1.0}
    assert g["grasp_quality"] == pytest.approx(plan.quality.objective)
    # A parametric hand has no joints: its postures carry no points.
    assert g["grasp_posture"]["points"] == [] and g["grasp_posture"]["joint_names"] == []


def test_bad_input_is_named_and_the_next_request_works(server):
    pts = can()
    pts[5, 1] = np.nan
    with Client(server.grpc) as c:
        with pytest.raises(grpc.RpcError) as e:
            c.plan_cloud(pts, hand="shadow")
        assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert field_of(e.value).startswith("cloud"), field_of(e.value)
        with pytest.raises(ValueError, match="grasp_type"):
            c.plan_cloud(can(), grasp_type="fist")
        with pytest.raises(grpc.RpcError) as e:
            c.plan_cloud(can(), hand="parallel_gripper", grasp_type="tripod")
        assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert len(c.plan_cloud(can(), hand="parallel_gripper", seed=1).contacts) == 2


def test_rgbd_frames_are_encoded_for_the_wire(server):
    color = np.zeros((48, 64, 3), np.uint8)
    depth = np.full((48, 64), 800, np.uint16)
    frame = rgbd_message(color, depth, 60.0, 60.0, 32.0, 24.0)
    assert (frame.depth.encoding, frame.depth.step, len(frame.depth.data)) == ("16UC1", 128, 48 * 64 * 2)
    assert (frame.color.encoding, frame.color.step) == ("rgb8", 192)
    with pytest.raises(ValueError, match="depth"):
        rgbd_message(color, depth[:10], 60.0, 60.0, 32.0, 24.0)
    with pytest.raises(ValueError, match="depth"):
        rgbd_message(color, depth.astype(np.int32), 60.0, 60.0, 32.0, 24.0)
    # A table 0.8 m below the camera and a red block 10 cm tall in the middle of the view.
    h, w = 120, 160
    color = np.full((h, w, 3), 150, np.uint8)
    depth = np.full((h, w), 800, np.uint16)
    color[50:70, 70:90] = (200, 40, 30)
    depth[50:70, 70:90] = 700
    with Client(server.grpc) as c:
        plan = c.plan_rgbd(color, depth, 150.0, 150.0, 79.5, 59.5, hand="parallel_gripper")
        # graspd loads its built-in grasp-type network by default.
        assert plan.contacts and plan.type_source == "model"
        assert plan.perception.objects == 1 and plan.perception.target_source == "saliency"
        roi = plan.perception.roi
        assert (roi.u_min, roi.v_min, roi.u_max, roi.v_max) == (70, 50, 90, 70)
        for contact in plan.contacts:
            assert abs(contact.position.z - 0.7) <= 0.1  # on the block (camera frame)
        with pytest.raises(grpc.RpcError) as e:
            c.plan_rgbd(color, np.zeros((h, w), np.uint16), 150.0, 150.0, 79.5, 59.5)
        assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert field_of(e.value) == "rgbd.depth.data"
        # By name: the red block is none of the objects the recogniser knows.
        with pytest.raises(grpc.RpcError) as e:
            c.plan_rgbd(color, depth, 150.0, 150.0, 79.5, 59.5, object="banana")
        assert e.value.code() == grpc.StatusCode.NOT_FOUND
        assert field_of(e.value) == "hints.object"
        assert "found: " in e.value.details()


def test_further_views_go_with_their_camera_poses(server):
    # A camera 0.8 m above a table, looking straight down (optical z = world −z).
    down = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 0.8], [0, 0, 0, 1.0]])
    h, w = 120, 160
    color = np.full((h, w, 3), 150, np.uint8)
    depth = np.full((h, w), 800, np.uint16)
    color[50:70, 70:90] = (200, 40, 30)
    depth[50:70, 70:90] = 700
    frame = rgbd_message(color, depth, 150.0, 150.0, 79.5, 59.5, camera_to_world=down)
    q = frame.camera_to_world.orientation
    # A half turn about x: quaternion (1, 0, 0, 0).
    assert abs(abs(q.x) - 1.0) < 1e-9 and abs(q.w) < 1e-9 and frame.camera_to_world.position.z == 0.8
    with pytest.raises(ValueError, match="camera_to_world"):
        rgbd_message(color, depth, 150.0, 150.0, 79.5, 59.5, camera_to_world=np.eye(3))
    unposed = rgbd_message(color, depth, 150.0, 150.0, 79.5, 59.5)
    with Client(server.grpc) as c:
        plan = c.plan_rgbd(color, depth, 150.0, 150.0, 79.5, 59.5, camera_to_world=down,
                           extra_views=[frame])
        assert plan.perception.fused_views == 1
        for contact in plan.contacts:
            assert abs(contact.position.z - 0.1) <= 0.1  # on the block (world frame)
        with pytest.raises(grpc.RpcError) as e:
            c.plan_rgbd(color, depth, 150.0, 150.0, 79.5, 59.5, camera_to_world=down,
                        extra_views=[unposed])
        assert field_of(e.value) == "extra_views[0].camera_to_world"


def raw_reading(t: int) -> Reading:
    """Raw classic-BioTac counts: at rest for 60 frames, then pressed (pdc up, electrodes down)."""
    pressed = t >= 60
    electrodes = [3000.0 + (t % 3)] * 19
    if pressed:
        for e in (16, 17, 1, 9):
            electrodes[e] -= 200.0
    return Reading(pdc=2000.0 + (120.0 if pressed else 0.0) + (t % 2), pac=[2000.0 + (t % 2)] * 22,
                   tdc=2500.0, tac=2000.0, electrodes=electrodes)


def test_a_stabilizer_session_answers_every_frame(server):
    with Client(server.grpc) as c:
        with c.stabilizer([Finger("th")]) as s:
            answers = [s.step(0.01 * t, [raw_reading(t)]) for t in range(120)]
    assert [a.frame_index for a in answers] == list(range(120))
    th = [a.fingers[0] for a in answers]
    assert not th[10].tared and th[55].tared
    assert th[40].mode == tactile_pb2.CONTROL_MODE_POSITION
    assert th[119].event != tactile_pb2.CONTACT_EVENT_NON_CONTACT
    assert th[119].mode == tactile_pb2.CONTROL_MODE_FORCE
    assert th[119].force > 0


def test_the_session_options_beyond_eq_6_9_reach_the_server(server):
    with Client(server.grpc) as c:
        with c.stabilizer([Finger("th")], latch_slip=True, centroid_slip_mm_s=20.0) as s:
            answers = [s.step(0.01 * t, [raw_reading(t)]) for t in range(80)]
        assert answers[-1].fingers[0].tared
        with pytest.raises(grpc.RpcError) as e:
            with c.stabilizer([Finger("th")], centroid_slip_mm_s=-1.0) as s:
                s.step(0.0, [raw_reading(0)])
    assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert field_of(e.value) == "session.centroid_slip_mm_s"


def test_an_electrodes_only_finger_needs_no_pac(server):
    with Client(server.grpc) as c:
        with c.stabilizer([Finger("ff", layout="biotac_sp", electrodes_only=True)]) as s:
            answers = [s.step(0.01 * t, [Reading(pdc=0.0, pac=[], tdc=0.0, tac=0.0,
                                                 electrodes=[3000.0 - (150.0 if t > 60 else 0.0)] * 24)])
                       for t in range(80)]
    assert answers[-1].fingers[0].tared
    assert answers[-1].fingers[0].event != tactile_pb2.CONTACT_EVENT_NON_CONTACT


def test_a_frame_out_of_order_ends_the_session_naming_the_field(server):
    with Client(server.grpc) as c:
        with c.stabilizer([Finger("th", pretared=True)]) as s:
            s.step(1.0, [raw_reading(0)])
            with pytest.raises(grpc.RpcError) as e:
                s.step(0.5, [raw_reading(1)])
    assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert field_of(e.value) == "frame.timestamp"


def test_a_reach_goes_round_the_obstacle_to_the_grasp(server):
    start = np.eye(4)
    start[:3, 3] = (0.0, 0.0, 0.4)
    goal = np.diag([1.0, -1.0, -1.0, 1.0])  # a top grasp: the hand's z down
    goal[:3, 3] = (0.5, 0.2, 0.1)
    post = ((0.25, 0.1, 0.15), (0.04, 0.04, 0.15))
    with Client(server.grpc) as c:
        r = c.plan_reach(start, goal, approach=(0, 0, -1), obstacles=[post],
                         support_plane=TABLE, hand_radius=0.04)
        end = r.samples[-1].pose.position
        assert np.allclose([end.x, end.y, end.z], goal[:3, 3])
        assert r.obstacle_clearance >= 0.01 and r.closest_obstacle == 0
        assert len(r.samples) == 211 and abs(r.samples[-1].time - 2.1) < 1e-9
        with pytest.raises(grpc.RpcError) as e:
            c.plan_reach(start, goal, obstacles=[((0.5, 0.2, 0.1), (0.05, 0.05, 0.05))])
        assert e.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert field_of(e.value) == "goal"
        with pytest.raises(ValueError, match="start"):
            c.plan_reach(np.zeros((3, 3)), goal)


def test_stubs_match_the_proto_files(tmp_path):
    subprocess.run([str(HERE.parent / "generate.sh"), str(tmp_path)], check=True,
                   env={"PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin"})
    committed = HERE.parent / "src" / "graspd" / "v1"
    fresh = tmp_path / "graspd" / "v1"
    names = sorted(p.name for p in fresh.glob("*.py"))
    assert names == sorted(p.name for p in committed.glob("*.py"))
    match, mismatch, errors = filecmp.cmpfiles(committed, fresh, names, shallow=False)
    assert not mismatch and not errors, f"run clients/python/generate.sh: {mismatch} {errors}"


def test_a_token_protected_server_takes_the_clients_token():
    from conftest import Server

    srv = Server("--auth-token", "s3cret-token")
    try:
        with Client(srv.grpc) as c:
            with pytest.raises(grpc.RpcError) as e:
                c.list_hands()
            assert e.value.code() == grpc.StatusCode.UNAUTHENTICATED
        with Client(srv.grpc, token="wrong") as c:
            with pytest.raises(grpc.RpcError) as e:
                c.list_hands()
            assert e.value.code() == grpc.StatusCode.UNAUTHENTICATED
        with Client(srv.grpc, token="s3cret-token") as c:
            assert any(h.name == "parallel_gripper" for h in c.list_hands())
            assert len(c.plan_cloud(can(), hand="parallel_gripper", seed=1).contacts) == 2
    finally:
        srv.stop()
