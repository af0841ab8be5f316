"""ROS 2 message types as cyclonedds-Python IdlStructs, written from the .msg files as rosidl maps
them (`pkg::msg::dds_::Name_`): the independent decoder of what rvc publishes on DDS
(/diagnostics of `rvc monitor --diagnostics` and `rvc hz --diagnostics`, std_msgs headers and
strings). Shared by the tests that need them; imported lazily (cyclonedds may be missing)."""
# No `from __future__ import annotations`: cyclonedds resolves the field types from the
# annotations themselves, and string annotations would name classes local to ros_idl_types().
import functools
import subprocess
from types import SimpleNamespace


def loopback_dds(rvc, tmp_path, monkeypatch):
    """Pins every Python participant to loopback with rvc's own generated config (checked to
    name `lo`), before any participant exists."""
    cfg = tmp_path / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    xml = cfg.read_text()
    assert 'name="lo"' in xml and "<AllowMulticast>false</AllowMulticast>" in xml
    monkeypatch.setenv("CYCLONEDDS_URI", f"file://{cfg}")


@functools.cache  # one set of classes: a sample must be of the class its topic was made with
def ros_idl_types():
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import array, int32, int64, sequence, uint8, uint32

    @dataclass
    class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
        sec: int32
        nanosec: uint32

    @dataclass
    class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
        stamp: Time_
        frame_id: str

    @dataclass
    class KeyValue_(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
        key: str
        value: str

    @dataclass
    class DiagnosticStatus_(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
        level: uint8  # `byte` in the .msg: one octet on the wire
        name: str
        message: str
        hardware_id: str
        values: sequence[KeyValue_]

    @dataclass
    class DiagnosticArray_(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
        header: Header_
        status: sequence[DiagnosticStatus_]

    @dataclass
    class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
        data: str

    @dataclass
    class Clock_(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
        clock: Time_

    @dataclass
    class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
        data: bool

    @dataclass
    class GearReport_(IdlStruct, typename="autoware_auto_vehicle_msgs::msg::dds_::GearReport_"):
        stamp: Time_
        report: uint8

    @dataclass
    class ServiceEventInfo_(IdlStruct, typename="service_msgs::msg::dds_::ServiceEventInfo_"):
        event_type: uint8
        stamp: Time_
        client_gid: array[uint8, 16]  # char[16] in the .msg: one octet each
        sequence_number: int64

    @dataclass
    class SetBool_Request_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Request_"):
        data: bool

    @dataclass
    class SetBool_Response_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Response_"):
        success: bool
        message: str

    @dataclass
    class SetBool_Event_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Event_"):
        info: ServiceEventInfo_
        request: sequence[SetBool_Request_, 1]
        response: sequence[SetBool_Response_, 1]

    return SimpleNamespace(Time_=Time_, Header_=Header_, KeyValue_=KeyValue_, DiagnosticStatus_=DiagnosticStatus_,
                           DiagnosticArray_=DiagnosticArray_, String_=String_, Clock_=Clock_, Bool_=Bool_,
                           GearReport_=GearReport_, ServiceEventInfo_=ServiceEventInfo_,
                           SetBool_Request_=SetBool_Request_, SetBool_Response_=SetBool_Response_,
                           SetBool_Event_=SetBool_Event_)
