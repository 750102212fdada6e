"""Topology model, formats and classes (paper §III-A/B)."""

from flyover.topology.canonical import canonical_form, class_id
from flyover.topology.classify import TopologyClass, classify, is_isomorphic
from flyover.topology.io import (
    read_graphml,
    read_topologies,
    read_yaml_spec,
    write_graphml,
    write_yaml_spec,
)
from flyover.topology.model import Connection, Kind, Label, Ramp, Road, Shape, Topology

__all__ = [
    "Kind", "Label", "Shape", "Road", "Ramp", "Connection", "Topology",
    "read_graphml", "write_graphml", "read_yaml_spec", "write_yaml_spec", "read_topologies",
    "canonical_form", "class_id", "TopologyClass", "classify", "is_isomorphic",
]
