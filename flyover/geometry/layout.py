"""A topology + a feature set → :class:`Interchange`: where each decision lives.

This module is the entry point (:func:`build_interchange`); each decision of the
layout has one home, which opens with what it decides and what it reads:

===================================  ==================================================
:mod:`flyover.geometry.settings`     settings (config ``geometry``) and a ramp's targets
:mod:`flyover.geometry.chains`       what a ramp is: its ends, movement, loop / stub / C-D
:mod:`flyover.geometry.roads`        road layout: carriageway lines, extents, levels
:mod:`flyover.geometry.levels`       level plan: crests of the flyovers, stub heights, room
:mod:`flyover.geometry.rails`        attachment windows: where along a parent a ramp attaches
:mod:`flyover.geometry.loop_room`    room between a loop and the connector round it
:mod:`flyover.geometry.free_end`     a stub's free end: height, how far out, beside what
:mod:`flyover.geometry.specs`        ramp specs: turn, pieces, length bound, leads, crest
:mod:`flyover.geometry.fitted`       the ramps fitted so far, as obstacles and parents
:mod:`flyover.geometry.collector`    collector-distributor roads (no search)
:mod:`flyover.geometry.state`        one build's parts wired together
:mod:`flyover.geometry.build`        the build / rebuild loop (lift, restarts, reroute,
                                     resampling, rebuilds)
:mod:`flyover.geometry.assemble`     the ``geometry.json`` value of a build
===================================  ==================================================
"""

from __future__ import annotations

from flyover.geometry.build import Interchange, RampOutcome, build_interchange
from flyover.geometry.settings import GeometryError, LayoutSettings, RampFeatures

__all__ = ["GeometryError", "LayoutSettings", "RampFeatures", "RampOutcome", "Interchange",
           "build_interchange"]
