"""ROS 2 message types as Cyclone DDS IDL structs, for talking to ROS 2 peers without ROS.

Each struct's `typename` is the DDS name ROS 2 gives the type
(`pkg::msg::dds_::Type_`) and its fields follow the ROS 2 `.msg` definition in
order and width (ros2/common_interfaces, builtin_interfaces from
ros2/rcl_interfaces, tf2_msgs from ros2/geometry2). All are final, key-less
and without optionals, so Cyclone writes them as plain XCDR1, as ROS 2 does.

TYPES maps a ROS 2 type name (`geometry_msgs/msg/Twist`) to its struct;
ros_topic() and qos() give the DDS topic name and QoS that ROS 2 uses.
"""
from dataclasses import dataclass, field

from cyclonedds.core import Policy, Qos
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, float64, int32, sequence, uint8, uint32, uint64
from cyclonedds.util import duration


def _dds(ros_name):
    package, _, name = ros_name.split("/")
    return f"{package}::msg::dds_::{name}_"


@dataclass
class Time(IdlStruct, typename=_dds("builtin_interfaces/msg/Time")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename=_dds("std_msgs/msg/Header")):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Vector3(IdlStruct, typename=_dds("geometry_msgs/msg/Vector3")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Twist(IdlStruct, typename=_dds("geometry_msgs/msg/Twist")):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistStamped(IdlStruct, typename=_dds("geometry_msgs/msg/TwistStamped")):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@dataclass
class Point(IdlStruct, typename=_dds("geometry_msgs/msg/Point")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename=_dds("geometry_msgs/msg/Quaternion")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename=_dds("geometry_msgs/msg/Pose")):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseWithCovariance(IdlStruct, typename=_dds("geometry_msgs/msg/PoseWithCovariance")):
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class TwistWithCovariance(IdlStruct, typename=_dds("geometry_msgs/msg/TwistWithCovariance")):
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class PoseStamped(IdlStruct, typename=_dds("geometry_msgs/msg/PoseStamped")):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class Transform(IdlStruct, typename=_dds("geometry_msgs/msg/Transform")):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename=_dds("geometry_msgs/msg/TransformStamped")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class Odometry(IdlStruct, typename=_dds("nav_msgs/msg/Odometry")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass
class LaserScan(IdlStruct, typename=_dds("sensor_msgs/msg/LaserScan")):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = field(default_factory=list)
    intensities: sequence[float32] = field(default_factory=list)


@dataclass
class TFMessage(IdlStruct, typename=_dds("tf2_msgs/msg/TFMessage")):
    transforms: sequence[TransformStamped] = field(default_factory=list)


@dataclass
class Image(IdlStruct, typename=_dds("sensor_msgs/msg/Image")):
    header: Header = field(default_factory=Header)
    height: uint32 = 0
    width: uint32 = 0
    encoding: str = ""
    is_bigendian: uint8 = 0
    step: uint32 = 0
    data: sequence[uint8] = field(default_factory=list)


@dataclass
class NodeVote(IdlStruct, typename=_dds("ubf_msgs/msg/NodeVote")):
    path: str = ""
    vote: float64 = 0.0
    weight: float64 = 0.0
    won: bool = False


@dataclass
class Tick(IdlStruct, typename=_dds("ubf_msgs/msg/Tick")):
    """ubf's own message (robots/src/ros2/schemas/ubf_msgs__Tick.msg), written here from its .msg."""
    stamp: Time = field(default_factory=Time)
    tick: uint64 = 0
    winner: str = ""
    linear: float64 = 0.0
    angular: float64 = 0.0
    stop: bool = False
    nodes: sequence[NodeVote] = field(default_factory=list)


TYPES = {
    f"{pkg}/msg/{cls.__name__}": cls
    for pkg, classes in {
        "builtin_interfaces": [Time],
        "std_msgs": [Header],
        "geometry_msgs": [Vector3, Twist, TwistStamped, Point, Quaternion, Pose, PoseWithCovariance,
                          TwistWithCovariance, PoseStamped, Transform, TransformStamped],
        "nav_msgs": [Odometry],
        "sensor_msgs": [LaserScan, Image],
        "tf2_msgs": [TFMessage],
        "ubf_msgs": [NodeVote, Tick],
    }.items()
    for cls in classes
}


def ros_topic(name, namespace=""):
    """The DDS topic of ROS 2 topic `name` (`/cmd_vel`, or `cmd_vel` under `namespace`)."""
    parts = [p for p in (namespace or "").split("/") + name.split("/") if p]
    return "rt/" + "/".join(parts)


def static_qos(reader=False):
    """tf2's static transform QoS: reliable, transient local (a reader that joins late gets each writer's last
    message), keep last 1 for a broadcaster, keep all for a listener."""
    return Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
               Policy.Durability.TransientLocal, Policy.History.KeepAll if reader else Policy.History.KeepLast(1))


def qos(sensor_data=False):
    """ROS 2's default QoS (reliable, volatile, keep last 10), or its sensor data QoS (best effort, keep last 5)."""
    if sensor_data:
        return Qos(Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepLast(5))
    return Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
               Policy.Durability.Volatile, Policy.History.KeepLast(10))
