"""OpenDRIVE export and validation (step 5): writer, reader, checks, plan drawing.

Import the submodules you need (``flyover.opendrive.writer``,
``flyover.opendrive.validate``, ...); this package stays light.
"""

__all__: list[str] = []
