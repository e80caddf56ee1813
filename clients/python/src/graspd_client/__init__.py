"""Python client of graspd over gRPC.

    import numpy as np
    from graspd_client import Client

    with Client("localhost:50051") as c:
        plan = c.plan_cloud(points, hand="shadow", seed=1, support_plane=((0, 0, 1), 0.0))
        print(plan.grasp_type, [ct.finger for ct in plan.contacts])

        # A reaching trajectory to a grasp from above, clear of a box (4x4 poses).
        goal = np.diag([1.0, -1.0, -1.0, 1.0]); goal[:3, 3] = (0.5, 0.2, 0.1)
        reach = c.plan_reach(start, goal, approach=(0, 0, -1), obstacles=[(centre, half)])

        with c.stabilizer([Finger("th", layout="biotac")]) as session:
            setpoint = session.step(t, [Reading(pdc, pac, tdc, tac, electrodes)])

The messages are the generated ones of ``graspd.v1`` (``proto/graspd/v1/*.proto``); the helpers
turn numpy arrays into them and back. Errors are ``grpc.RpcError`` with the server's status;
``field_of(error)`` gives the request field the server named.
"""

from __future__ import annotations

import collections
import queue
from dataclasses import dataclass, field
from typing import Iterable, Optional, Sequence

import grpc
import numpy as np

from google.protobuf import json_format

from graspd.v1 import (
    common_pb2,
    grasp_planner_pb2_grpc,
    hand_pb2,
    plan_pb2,
    reach_pb2,
    ros_pb2,
    tactile_stabilizer_pb2 as tactile_pb2,
    tactile_stabilizer_pb2_grpc,
)

__all__ = [
    "Client",
    "Finger",
    "Reading",
    "StabilizerSession",
    "cloud_message",
    "field_of",
    "moveit_grasps_of",
    "pointcloud2_from_ros",
    "pointcloud2_message",
    "rgbd_message",
    "points_of",
]

GRASP_TYPES = {
    "large_wrap": common_pb2.GRASP_TYPE_LARGE_WRAP,
    "small_wrap": common_pb2.GRASP_TYPE_SMALL_WRAP,
    "power": common_pb2.GRASP_TYPE_POWER,
    "pinch": common_pb2.GRASP_TYPE_PINCH,
    "precision": common_pb2.GRASP_TYPE_PRECISION,
    "tripod": common_pb2.GRASP_TYPE_TRIPOD,
}


def field_of(error: grpc.RpcError) -> Optional[str]:
    """The request field an INVALID_ARGUMENT names (the ``graspd-field`` trailer), if any."""
    for key, value in (error.trailing_metadata() or ()):
        if key == "graspd-field":
            return value
    return None


def _xyz(array, name: str) -> np.ndarray:
    a = np.asarray(array, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected an (N, 3) array, got shape {a.shape}")
    return a


def cloud_message(points, normals=None, frame_id: str = "") -> plan_pb2.PointCloud:
    """An (N, 3) array in metres (and optional unit normals) as the packed float32 cloud."""
    p = _xyz(points, "points")
    msg = plan_pb2.PointCloud(points=p.astype("<f4").tobytes(), frame_id=frame_id)
    if normals is not None:
        n = _xyz(normals, "normals")
        if n.shape != p.shape:
            raise ValueError(f"normals: shape {n.shape} does not match points {p.shape}")
        msg.normals = n.astype("<f4").tobytes()
    return msg


def points_of(msg: plan_pb2.PointCloud) -> np.ndarray:
    """The packed cloud back as an (N, 3) float64 array."""
    return np.frombuffer(msg.points, dtype="<f4").reshape(-1, 3).astype(np.float64)


FLOAT32 = 7  # sensor_msgs/PointField.FLOAT32


def pointcloud2_message(points, normals=None, frame_id: str = "") -> ros_pb2.PointCloud2:
    """An (N, 3) array, or an organised (H, W, 3) one with NaN for invalid pixels, in metres (and
    optional unit normals of the same shape) as a little-endian float32 sensor_msgs/PointCloud2
    (x, y, z[, normal_x, normal_y, normal_z])."""
    a = np.asarray(points, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 3:
        height, width = a.shape[:2]
    elif a.ndim == 2 and a.shape[1] == 3:
        height, width = 1, a.shape[0]
    else:
        raise ValueError(f"points: expected an (N, 3) or (H, W, 3) array, got shape {a.shape}")
    columns = [a.reshape(-1, 3)]
    names = ["x", "y", "z"]
    if normals is not None:
        n = np.asarray(normals, dtype=np.float64)
        if n.shape != a.shape:
            raise ValueError(f"normals: shape {n.shape} does not match points {a.shape}")
        columns.append(n.reshape(-1, 3))
        names += ["normal_x", "normal_y", "normal_z"]
    data = np.concatenate(columns, axis=1).astype("<f4")
    step = 4 * len(names)
    return ros_pb2.PointCloud2(
        height=height,
        width=width,
        fields=[ros_pb2.PointField(name=nm, offset=4 * i, datatype=FLOAT32, count=1)
                for i, nm in enumerate(names)],
        is_bigendian=False,
        point_step=step,
        row_step=step * width,
        data=data.tobytes(),
        is_dense=not np.isnan(a).any(),
        frame_id=frame_id,
    )


def pointcloud2_from_ros(msg) -> ros_pb2.PointCloud2:
    """A ROS ``sensor_msgs/PointCloud2`` (rclpy or rospy message, or anything with its fields) as
    graspd's message, field for field: the bytes go as the driver wrote them."""
    return ros_pb2.PointCloud2(
        height=msg.height,
        width=msg.width,
        fields=[ros_pb2.PointField(name=f.name, offset=f.offset, datatype=f.datatype,
                                   count=f.count) for f in msg.fields],
        is_bigendian=bool(msg.is_bigendian),
        point_step=msg.point_step,
        row_step=msg.row_step,
        data=bytes(msg.data),
        is_dense=bool(msg.is_dense),
        frame_id=msg.header.frame_id,
    )


def moveit_grasps_of(plan: plan_pb2.PlanGraspResponse) -> list:
    """The plan's ``moveit_grasps`` as dicts in the layout of ROS 2's moveit_msgs/msg/Grasp (field
    names and nesting), ready for ``rosidl_runtime_py.set_message_fields(Grasp(), d)``."""
    return [
        json_format.MessageToDict(g, preserving_proto_field_name=True,
                                  always_print_fields_with_no_presence=True)
        for g in plan.moveit_grasps
    ]


def _image(array: np.ndarray, encoding: str) -> plan_pb2.Image:
    a = np.ascontiguousarray(array)
    height, width = a.shape[:2]
    return plan_pb2.Image(
        width=width, height=height, encoding=encoding, step=a.strides[0], data=a.tobytes()
    )


def rgbd_message(
    color: np.ndarray,
    depth: np.ndarray,
    fx: float,
    fy: float,
    cx: float,
    cy: float,
    color_encoding: str = "rgb8",
    depth_scale: float = 0.0,
    camera_to_world=None,
) -> plan_pb2.RgbdFrame:
    """An (H, W, 3) uint8 colour image and an (H, W) depth image (uint16 millimetres as 16UC1,
    or float32 metres as 32FC1) with pinhole intrinsics, as an RgbdFrame. ``camera_to_world``: the
    camera's pose as a 4x4 homogeneous matrix (optical frame: x right, y down, z forward); plans
    are then in the world frame, and the frame can be fused with others (``extra_views``)."""
    color = np.asarray(color)
    depth = np.asarray(depth)
    if color.ndim != 3 or color.shape[2] != 3 or color.dtype != np.uint8:
        raise ValueError(f"color: expected an (H, W, 3) uint8 array, got {color.shape} {color.dtype}")
    if depth.dtype == np.uint16:
        depth_encoding = "16UC1"
    elif depth.dtype == np.float32:
        depth_encoding = "32FC1"
    else:
        raise ValueError(f"depth: expected uint16 (mm) or float32 (m), got {depth.dtype}")
    if depth.shape != color.shape[:2]:
        raise ValueError(f"depth: shape {depth.shape} does not match color {color.shape[:2]}")
    frame = plan_pb2.RgbdFrame(
        color=_image(color, color_encoding),
        depth=_image(depth.astype(depth.dtype.newbyteorder("<")), depth_encoding),
        intrinsics=plan_pb2.CameraIntrinsics(fx=fx, fy=fy, cx=cx, cy=cy),
        depth_scale=depth_scale,
    )
    if camera_to_world is not None:
        frame.camera_to_world.CopyFrom(_pose(camera_to_world))
    return frame


def _pose(matrix, name: str = "camera_to_world") -> common_pb2.Pose:
    """A 4x4 homogeneous rigid transform as a Pose (position + unit quaternion x, y, z, w)."""
    m = np.asarray(matrix, dtype=float)
    if m.shape != (4, 4) or not np.allclose(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"{name}: expected a 4x4 homogeneous matrix, got {m.shape}")
    r = m[:3, :3]
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
        raise ValueError(f"{name}: the rotation part is not a rotation")
    # Shepperd's method: the largest of w, x, y, z first, for accuracy.
    t = np.trace(r)
    k = int(np.argmax([t, r[0, 0], r[1, 1], r[2, 2]]))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    else:
        i, j, l = [(0, 1, 2), (1, 2, 0), (2, 0, 1)][k - 1]
        s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[l, l])
        v = [0.0, 0.0, 0.0]
        v[i] = 0.25 * s
        v[j] = (r[j, i] + r[i, j]) / s
        v[l] = (r[l, i] + r[i, l]) / s
        q = ((r[l, j] - r[j, l]) / s, *v)
    w, x, y, z = q
    return common_pb2.Pose(position=_vec3(m[:3, 3]),
                           orientation=common_pb2.Quaternion(x=x, y=y, z=z, w=w))


def _vec3(v) -> common_pb2.Vec3:
    x, y, z = (float(c) for c in v)
    return common_pb2.Vec3(x=x, y=y, z=z)


@dataclass
class Finger:
    """One finger of a tactile session: a built-in layout name ("biotac", "biotac_sp").
    ``electrodes_only``: the sensor gives only its electrodes (send pac=[] and zeros for pdc,
    tdc, tac); slip then comes from the contact centroid's motion."""

    name: str
    layout: str = "biotac"
    pretared: bool = False
    baseline_frames: Optional[int] = None
    electrodes_only: bool = False


@dataclass
class Reading:
    """One finger's raw reading of a frame: pac as one value or the driver's 22 samples."""

    pdc: float
    pac: Sequence[float]
    tdc: float
    tac: float
    electrodes: Sequence[float] = field(default_factory=list)


class StabilizerSession:
    """A ``Stabilize`` stream: ``step`` sends one frame and returns its setpoint (one answer per
    frame, in order). Closing the session ends the stream and frees the server's slot."""

    def __init__(self, stub, session: tactile_pb2.TactileSession, timeout: Optional[float]):
        self._requests: "queue.Queue[Optional[tactile_pb2.StabilizeRequest]]" = queue.Queue()
        self._requests.put(tactile_pb2.StabilizeRequest(session=session))
        self._call = stub.Stabilize(iter(self._requests.get, None), timeout=timeout)
        self.frames = 0

    def step(self, timestamp: float, readings: Iterable[Reading]) -> tactile_pb2.StabilizationSetpoint:
        frame = tactile_pb2.TactileFrame(timestamp=float(timestamp))
        for r in readings:
            pac = [float(r.pac)] if np.isscalar(r.pac) else [float(v) for v in r.pac]
            frame.fingers.append(
                tactile_pb2.FingerReading(
                    pdc=float(r.pdc),
                    pac=pac,
                    tdc=float(r.tdc),
                    tac=float(r.tac),
                    electrodes=[float(e) for e in r.electrodes],
                )
            )
        self._requests.put(tactile_pb2.StabilizeRequest(frame=frame))
        answer = next(self._call)
        self.frames += 1
        return answer

    def close(self) -> None:
        self._requests.put(None)
        self._call.cancel()

    def __enter__(self) -> "StabilizerSession":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class _ClientCallDetails(
        collections.namedtuple("_ClientCallDetails",
                               ("method", "timeout", "metadata", "credentials", "wait_for_ready",
                                "compression")),
        grpc.ClientCallDetails):
    pass


class _Bearer(grpc.UnaryUnaryClientInterceptor, grpc.StreamStreamClientInterceptor):
    """Adds ``authorization: Bearer <token>`` to every call."""

    def __init__(self, token: str):
        self._header = ("authorization", f"Bearer {token}")

    def _details(self, d):
        metadata = list(d.metadata or ()) + [self._header]
        return _ClientCallDetails(d.method, d.timeout, metadata, d.credentials,
                                  getattr(d, "wait_for_ready", None),
                                  getattr(d, "compression", None))

    def intercept_unary_unary(self, continuation, client_call_details, request):
        return continuation(self._details(client_call_details), request)

    def intercept_stream_stream(self, continuation, client_call_details, request_iterator):
        return continuation(self._details(client_call_details), request_iterator)


class Client:
    """A connection to graspd's gRPC port. ``token``: the bearer token of a server with
    authentication on (sent as ``authorization: Bearer …`` with every call)."""

    def __init__(self, address: str = "localhost:50051", timeout: Optional[float] = 30.0,
                 max_message_bytes: int = 64 << 20, token: Optional[str] = None):
        options = [
            ("grpc.max_send_message_length", max_message_bytes),
            ("grpc.max_receive_message_length", max_message_bytes),
        ]
        self._raw_channel = grpc.insecure_channel(address, options=options)
        self._channel = (grpc.intercept_channel(self._raw_channel, _Bearer(token))
                         if token is not None else self._raw_channel)
        self._planner = grasp_planner_pb2_grpc.GraspPlannerStub(self._channel)
        self._tactile = tactile_stabilizer_pb2_grpc.TactileStabilizerStub(self._channel)
        self.timeout = timeout

    def close(self) -> None:
        self._raw_channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def list_hands(self) -> Sequence[hand_pb2.HandDescription]:
        return list(self._planner.ListHands(hand_pb2.ListHandsRequest(), timeout=self.timeout).hands)

    def get_hand(self, name: str) -> hand_pb2.HandDescription:
        return self._planner.GetHand(hand_pb2.GetHandRequest(name=name), timeout=self.timeout).hand

    def hand_synergies(self, name: str) -> hand_pb2.HandSynergies:
        """A hand's posture synergies (dissertation 7.3; hands with kinematics only): the mean
        posture, the principal components and each grasp type's centre. The first call for a
        hand fits them (seconds); give the client a timeout that allows it."""
        return self._planner.GetHandSynergies(hand_pb2.GetHandSynergiesRequest(name=name),
                                              timeout=self.timeout)

    def plan(self, request: plan_pb2.PlanGraspRequest) -> plan_pb2.PlanGraspResponse:
        return self._planner.PlanGrasp(request, timeout=self.timeout)

    def plan_reach(self, start, goal, approach=None, obstacles=(), support_plane=None,
                   hand_radius: Optional[float] = None,
                   pregrasp_distance: Optional[float] = None,
                   **options) -> reach_pb2.PlanReachResponse:
        """A reaching trajectory from ``start`` to the grasp ``goal`` (4x4 hand poses, world),
        the last ``pregrasp_distance`` along ``approach``; ``obstacles``: (centre, half_extents)
        pairs of axis-aligned boxes; ``support_plane``: ((nx, ny, nz), offset); ``options``:
        ReachOptions fields (reach_duration, approach_duration, time_step, horizon,
        min_clearance). The answer's ``samples`` hold time, pose and velocity."""
        request = reach_pb2.PlanReachRequest(
            start=_pose(start, "start"),
            goal=_pose(goal, "goal"),
            obstacles=[reach_pb2.Obstacle(centre=_vec3(c), half_extents=_vec3(h))
                       for c, h in obstacles],
            options=reach_pb2.ReachOptions(**options),
        )
        if approach is not None:
            request.approach.CopyFrom(_vec3(approach))
        if support_plane is not None:
            request.support_plane.CopyFrom(
                common_pb2.Plane(normal=_vec3(support_plane[0]), offset=support_plane[1]))
        if hand_radius is not None:
            request.hand_radius = hand_radius
        if pregrasp_distance is not None:
            request.pregrasp_distance = pregrasp_distance
        return self._planner.PlanReach(request, timeout=self.timeout)

    def plan_cloud(
        self,
        points,
        hand: str = "parallel_gripper",
        seed: int = 0,
        normals=None,
        grasp_type: Optional[str] = None,
        support_plane=None,
        viewpoint=None,
        attention_point=None,
        without_opposition: bool = False,
    ) -> plan_pb2.PlanGraspResponse:
        """Plans on an (N, 3) array in metres. ``support_plane`` is ``(normal, offset)`` with
        n·x + offset = 0 and n toward the object; ``grasp_type`` forces a type by name."""
        return self.plan(
            self._request(
                plan_pb2.PlanGraspRequest(cloud=cloud_message(points, normals)),
                hand, seed, grasp_type, support_plane, viewpoint, attention_point,
                without_opposition,
            )
        )

    def plan_pointcloud2(
        self,
        cloud: ros_pb2.PointCloud2,
        hand: str = "parallel_gripper",
        seed: int = 0,
        moveit_grasps: bool = False,
        candidates: Optional[int] = None,
        **kwargs,
    ) -> plan_pb2.PlanGraspResponse:
        """Plans on a PointCloud2 (``pointcloud2_message`` or ``pointcloud2_from_ros``); with
        ``moveit_grasps`` the response carries each ranked candidate as a moveit_msgs/Grasp
        (``moveit_grasps_of``). Other keywords as for ``plan_cloud``."""
        request = self._request(
            plan_pb2.PlanGraspRequest(cloud2=cloud), hand, seed,
            kwargs.pop("grasp_type", None), kwargs.pop("support_plane", None),
            kwargs.pop("viewpoint", None), kwargs.pop("attention_point", None),
            kwargs.pop("without_opposition", False),
        )
        if kwargs:
            raise TypeError(f"unexpected arguments: {sorted(kwargs)}")
        request.output.moveit_grasps = moveit_grasps
        if candidates is not None:
            request.options.candidates = int(candidates)
        return self.plan(request)

    def plan_rgbd(self, color, depth, fx, fy, cx, cy, hand: str = "parallel_gripper",
                  seed: int = 0, camera_to_world=None,
                  extra_views: Sequence[plan_pb2.RgbdFrame] = (),
                  object: Optional[str] = None,
                  **kwargs) -> plan_pb2.PlanGraspResponse:
        """Plans on an RGB-D frame (see ``rgbd_message``). ``extra_views``: further frames of the
        same scene, each built by ``rgbd_message`` with its ``camera_to_world`` (as this frame
        then needs too); graspd adds what they see of the target object to this frame's points.
        ``object``: plan for the object graspd's recogniser takes for this name ("apple"); a
        name it does not know, or no such object in view, raises ``grpc.RpcError`` with
        NOT_FOUND naming the objects found."""
        frame = rgbd_message(color, depth, fx, fy, cx, cy,
                             color_encoding=kwargs.pop("color_encoding", "rgb8"),
                             depth_scale=kwargs.pop("depth_scale", 0.0),
                             camera_to_world=camera_to_world)
        request = plan_pb2.PlanGraspRequest(rgbd=frame)
        request.extra_views.extend(extra_views)
        if object is not None:
            request.hints.object = object
        return self.plan(
            self._request(request, hand, seed,
                          kwargs.pop("grasp_type", None), None, None, None, False)
        )

    @staticmethod
    def _request(request, hand, seed, grasp_type, support_plane, viewpoint, attention_point,
                 without_opposition) -> plan_pb2.PlanGraspRequest:
        request.hand_name = hand
        request.options.seed = int(seed)
        if without_opposition:
            request.options.mode = common_pb2.PLANNER_MODE_WITHOUT_OPPOSITION
        if grasp_type is not None:
            if grasp_type not in GRASP_TYPES:
                raise ValueError(f"grasp_type: one of {sorted(GRASP_TYPES)}, got {grasp_type!r}")
            request.hints.grasp_type = GRASP_TYPES[grasp_type]
        if support_plane is not None:
            normal, offset = support_plane
            request.hints.support_plane.normal.CopyFrom(_vec3(normal))
            request.hints.support_plane.offset = float(offset)
        if viewpoint is not None:
            request.hints.viewpoint.CopyFrom(_vec3(viewpoint))
        if attention_point is not None:
            request.hints.attention_point.CopyFrom(_vec3(attention_point))
        return request

    def stabilizer(self, fingers: Sequence[Finger], calibration_gain: Optional[float] = None,
                   **law) -> StabilizerSession:
        """Opens a tactile session; ``law`` may set f0, delta_material, delta_slip, f_min,
        f_max, window_length, stride, alpha, latch_slip (each slip episode raises f_d by
        delta_slip until contact is lost) and centroid_slip_mm_s (slip also when the contact
        centroid moves faster than this)."""
        session = tactile_pb2.TactileSession()
        for f in fingers:
            finger = session.fingers.add(name=f.name, layout_name=f.layout,
                                         electrodes_only=f.electrodes_only)
            finger.tare.pretared = f.pretared
            if f.baseline_frames is not None:
                finger.tare.baseline_frames = f.baseline_frames
        if calibration_gain is not None:
            session.calibration_gain = calibration_gain
        for key, value in law.items():
            setattr(session, key, value)
        return StabilizerSession(self._tactile, session, timeout=None)
