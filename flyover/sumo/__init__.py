"""SUMO networks from OpenDRIVE: ``netconvert`` and routability checks (sumolib)."""

__all__: list[str] = []
