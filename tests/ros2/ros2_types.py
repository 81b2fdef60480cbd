"""ROS 2 message types as Cyclone DDS IDL dataclasses, with ROS 2's DDS names (`pkg::msg::dds_::Type_`).

These are the independent implementation the node is tested against: their CDR layout is Cyclone's,
written here from the `.msg` definitions (sensor_msgs/Image, std_msgs/String, diagnostic_msgs and
ros/presrs_msgs), not from presrs's code.
"""

from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int32, int64, sequence, uint8, uint16, uint32, uint64


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header
    height: uint32
    width: uint32
    encoding: str
    is_bigendian: uint8
    step: uint32
    data: sequence[uint8]


@dataclass
class MultiArrayDimension(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayDimension_"):
    label: str
    size: uint32
    stride: uint32


@dataclass
class MultiArrayLayout(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayLayout_"):
    dim: sequence[MultiArrayDimension]
    data_offset: uint32


@dataclass
class Float32MultiArray(IdlStruct, typename="std_msgs::msg::dds_::Float32MultiArray_"):
    layout: MultiArrayLayout
    data: sequence[float32]


@dataclass
class UInt16MultiArray(IdlStruct, typename="std_msgs::msg::dds_::UInt16MultiArray_"):
    layout: MultiArrayLayout
    data: sequence[uint16]


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: sequence[DiagnosticStatus]


# ros/presrs_msgs/msg/TerrainDecision.msg (its DECIDED_AT_* constants: DECIDED_AT below)
DECIDED_AT = {"none": 0, "liftoff": 1, "offset": 2, "length": 3}


@dataclass
class TerrainDecision(IdlStruct, typename="presrs_msgs::msg::dds_::TerrainDecision_"):
    header: Header
    stance: uint64
    kind: str
    label: str
    class_index: uint32
    class_names: sequence[str]
    confidence: float64
    posteriors: sequence[float64]
    touchdown_frame: uint64
    sample_frame: uint64
    frame: uint64
    frames_used: uint32
    decided_at: uint8
    decided_at_frame: uint64
    decided_at_stamp: Time
    cut: bool
    touchdown_stamp: Time
    liftoff_stamp: Time
    gait: str
    latency_us: float64
    early_rule: str
    early_reason: str
    early_point: int64
    early_frames: uint64
    early_threshold: float64
    gap_frames: uint32
    has_novelty: bool
    unknown: bool
    nearest: str
    novelty: float64
    novelty_threshold: float64
    credibility: float64


# ros/presrs_msgs/msg/StanceEvent.msg
@dataclass
class StanceEvent(IdlStruct, typename="presrs_msgs::msg::dds_::StanceEvent_"):
    header: Header
    event: uint8
    stance: uint64
    touchdown_frame: uint64
    end_frame: uint64
    frame: uint64
    partial: bool
    peak_frame: uint64
    peak_load: float64
    sampled: bool
    touchdown_stamp: Time
    liftoff_stamp: Time
    gap_frames: uint32
