"""DDS: ROS 2 on the wire (rmw_cyclonedds's names, XCDR1 bytes, service headers), and the edges
between the hosts of one graph."""

from ._discovery import DiscoveryInfo
from ._domain import (
    HOST_LEASE,
    MAX_DOMAIN_ID,
    SERVICE_QOS,
    DdsDomain,
    config_xml,
    dds_qos,
    default_domain_id,
    participant_gid,
)
from ._edges import DdsEdgeReader, DdsEdgeWriter, edge_topic
from ._endpoints import (
    DdsServiceClient,
    DdsServiceServer,
    DdsTopicReader,
    DdsTopicWriter,
    type_hash_user_data,
)
from ._idl import REQUEST_HEADER_FIELDS, idl_type
from ._names import DISCOVERY_TOPIC, DISCOVERY_TYPE, dds_type_name, reply_topic, request_topic, topic_name
from ._transport import DdsTransport

__all__ = [
    "DISCOVERY_TOPIC",
    "DISCOVERY_TYPE",
    "HOST_LEASE",
    "MAX_DOMAIN_ID",
    "REQUEST_HEADER_FIELDS",
    "SERVICE_QOS",
    "DdsDomain",
    "DdsEdgeReader",
    "DdsEdgeWriter",
    "DdsServiceClient",
    "DdsServiceServer",
    "DdsTopicReader",
    "DdsTopicWriter",
    "DdsTransport",
    "DiscoveryInfo",
    "config_xml",
    "dds_qos",
    "dds_type_name",
    "default_domain_id",
    "edge_topic",
    "idl_type",
    "participant_gid",
    "reply_topic",
    "request_topic",
    "topic_name",
    "type_hash_user_data",
]
