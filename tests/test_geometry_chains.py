"""What each ramp is, read from the topology (:mod:`flyover.geometry.chains`)."""

from flyover.geometry.chains import ends, road_of
from flyover.topology.model import Label


def test_ends_and_road_of_are_read_once_per_topology(j1):
    first = ends(j1, "r2")
    assert first == (("r1", Label.OUT_L), ("r3", Label.IN_L))
    assert ends(j1, "r2") is first  # kept with the topology, not read from the graph again
    assert road_of(j1, "r2", True) == "R4" and road_of(j1, "r2", False) == "R1"
    assert j1.derived("road_of")[("r2", True)] == "R4"


def test_each_topology_keeps_its_own_ends(j1):
    swapped = j1.relabeled({"R3": "R4", "R4": "R3"})
    assert ends(j1, "r1")[1] == ("R3", Label.IN_R)
    assert ends(swapped, "r1")[1] == ("R4", Label.IN_R)  # nothing kept from j1
    assert road_of(j1, "r2", True) == "R4" and road_of(swapped, "r2", True) == "R3"
    assert swapped.derived("ends") is not j1.derived("ends")
