"""AV-research clients of our OpenDRIVE (CommonRoad, Lanelet2, pyopendrive, pyxodr), run as tools."""
