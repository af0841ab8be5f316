"""A ROS 2 node as DDS shows it, from cyclonedds-Python: what a ROS 2 bridge needs besides the
`rt/` topics themselves.

zenoh-plugin-ros2dds routes a DDS writer or reader only once a ROS 2 node claims it: rmw writes a
`ParticipantEntitiesInfo` sample on the DDS topic `ros_discovery_info` (type
`rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_`) listing each node's reader and writer GIDs,
and the plugin matches those GIDs with the endpoints DDS discovery reports. A bare DDS writer on
`rt/x` is discovered but never bridged. The layout is rmw_dds_common's .msg files from ROS 2 Iron
on (a GID is 16 bytes, `uint8[16] data`), which the plugin assumes when ROS_DISTRO is unset; the
GID of an entity is its DDS GUID (12-byte prefix + 4-byte entity id), as rmw_cyclonedds sets it.
"""
# No `from __future__ import annotations`: cyclonedds reads the field types from the annotations.


def rmw_types():
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import array, bounded_str, sequence, uint8

    @dataclass
    class Gid_(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
        data: array[uint8, 16]

    @dataclass
    class NodeEntitiesInfo_(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
        node_namespace: bounded_str[256]
        node_name: bounded_str[256]
        reader_gid_seq: sequence[Gid_]
        writer_gid_seq: sequence[Gid_]

    @dataclass
    class ParticipantEntitiesInfo_(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
        gid: Gid_
        node_entities_info_seq: sequence[NodeEntitiesInfo_]

    return Gid_, NodeEntitiesInfo_, ParticipantEntitiesInfo_


def gid_of(entity, Gid_):
    return Gid_(data=list(entity.guid.bytes))


def announce_node(participant, name, writers=(), readers=(), namespace="/"):
    """Publishes the node `namespace/name` owning `writers` and `readers` on ros_discovery_info, with
    rmw's QoS for it (reliable, transient-local, keep-last 1) so a bridge started later still reads
    it. Returns the DataWriter: keep it alive as long as the node should exist."""
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    Gid_, NodeEntitiesInfo_, ParticipantEntitiesInfo_ = rmw_types()
    topic = Topic(participant, "ros_discovery_info", ParticipantEntitiesInfo_)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=10)), Policy.Durability.TransientLocal,
              Policy.History.KeepLast(1), Policy.DataRepresentation(use_cdrv0_representation=True))
    writer = DataWriter(participant, topic, qos=qos)
    node = NodeEntitiesInfo_(node_namespace=namespace, node_name=name,
                             reader_gid_seq=[gid_of(r, Gid_) for r in readers],
                             writer_gid_seq=[gid_of(w, Gid_) for w in writers])
    writer.write(ParticipantEntitiesInfo_(gid=gid_of(participant, Gid_), node_entities_info_seq=[node]))
    return writer
