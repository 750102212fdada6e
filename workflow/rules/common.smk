# Shared helpers: config validation, city discovery, input functions,
# wildcard constraints. No rule lives here.
import json
import sys
from pathlib import Path

from flyover.config import validate_config
from flyover.summary import status_lines
from flyover.topology.io import TOPOLOGY_SUFFIXES


validate_config(config, "config/config.yaml")

# Bump a stage's version when its algorithm changes: params are rerun triggers.
TOPOLOGY_VERSION = 7  # 2: representative.graphml per class; 3: safe names, FLYOVER ids; 4: pyosmium OSM reader; 5: OSM connectors between roads, ref-less carriageways paired by name, 3+ motorway link groups one interchange, direct ramps with geometry, self-check legs by carriageway pairs; 6: a carriageway turning back by over 90° at one node is two (DC US 50 stub: one road 7 → two, 8 roads); 7: OSM ramps carry turn_deg (their real heading change) in the GraphML
# export 2: one job per class; 3: auxiliary lanes beside tapers, weaving sections
EXPORT_VERSION = 14  # 4: every continuing lane linked (gore shoulders from zero width), joins snapped; 5: plan.png in 40 m chunks, fixed layout; 6: connecting roads taper over 2/3 of the section (CommonRoad); 7: a straight-on branch of a fork or join changes its lane width over a taper on its body, not the connecting road; 8: paramPoly3 records cut so that road position s is within 5 cm of arc length (heights were up to 356 m from their place); 9: the lanes of a two-lane speed-change region close (open) one at a time, each over its own taper; 10: paramPoly3 parts within 0.25 m of arc length (was 5 cm; ~30 % smaller files, faster checks); 11: where a carriageway ends into (begins from) a narrower ramp straight on, the lanes beyond the ramp's close (open) one at a time on its body, each over its own taper (two together on the T designs and trumpet); 12: a lane that opens from zero width stops widening 1e-5 of its taper before the taper's end (CommonRoad's converter missed the end and re-drew the lane over its whole lanelet: 1-2 cm join/split errors); 13: width, offset and height cubics' b, c, d to 15 significant digits (12 decimals left a closing lane 2.6e-7 m wide at its end, above CommonRoad's 1e-8 m: its polylines_intersection errors); 14: the lanes that go on past a width transition of several tapers change their width over the whole transition, not its first taper (DC r4: 276 m read back as 239 m on the lane centre)
VALIDATION_VERSION = 6  # 4: one job per class, the SUMO network of the export stage; 5: clearance compares a ramp with itself (a loop over its own lane); 6: clearance samples thinned to 4 per metre (same conflicts, 4x faster)
CLIENTS_SAMPLE_VERSION = 2  # 1: CommonRoad's map verifier on one seeded interchange; 2: among the smallest tenth


wildcard_constraints:
    city=r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}",
    class_id=r"c[0-9a-f]{10}",


def city_names():
    """Cities to build: config `cities`, else every folder of cities_dir (names checked)."""
    from flyover.topology.city import city_names as checked_city_names

    return checked_city_names(config["cities_dir"], config["cities"])


CITIES = city_names()


def print_summary(log, failed=False):
    """At the end of a run: per stage what was built, what failed, the tables to look in."""
    head = "flyover: the run stopped on a failed job" if failed else "flyover: done"
    print("\n".join([head, *status_lines("results")]), file=sys.stderr)


def city_files(wildcards):
    """The topology files of one city (GraphML, YAML specs, OSM extracts)."""
    root = Path(config["cities_dir"]) / wildcards.city
    return sorted(
        str(p)
        for p in root.iterdir()
        if p.is_file() and p.suffix.lower() in TOPOLOGY_SUFFIXES
    )


def city_osm_options(wildcards):
    """The osm: section for one city: its own bbox only (another city's is no rerun trigger)."""
    opts = {k: v for k, v in config["osm"].items() if k != "city_bbox"}
    box = config["osm"].get("city_bbox", {}).get(wildcards.city)
    if box is not None:
        opts["bbox"] = box
    return opts


def class_manifest():
    """The classify checkpoint's manifest (class id → representative etc.)."""
    path = checkpoints.classify.get().output.manifest
    return json.loads(Path(path).read_text(encoding="utf-8"))


def class_ids():
    return sorted(class_manifest()["classes"])


def class_representative(wildcards):
    """The class's representative topology, written by the classify checkpoint beside its
    manifest at a path of the class's own, rewritten only when it changes (a new city whose
    interchanges join existing classes does not rerun them)."""
    class_manifest()["classes"][wildcards.class_id]  # the class exists once classified
    return f"results/classes/{wildcards.class_id}/representative.graphml"


def class_name(wildcards):
    """The readable name of a class (catalog design or shape-roads-ramps)."""
    return class_manifest()["classes"][wildcards.class_id]["class_name"]


def class_topology_outputs(wildcards):
    return expand(
        "results/classes/{class_id}/topology.{ext}",
        class_id=class_ids(),
        ext=["graphml", "png"],
    )


# -- sampling (step 3) --

def class_feature_tables(wildcards):
    """Every class's feature sets (results/features/{class_id}.parquet)."""
    return expand("results/features/{class_id}.parquet", class_id=class_ids())


def class_coverage_rows(wildcards):
    """Every class's row of coverage.parquet, kept per class so one class reruns alone."""
    return expand("results/coverage/{class_id}.parquet", class_id=class_ids())


# -- per-class stages (geometry, export, validation, ...) --

def class_tables(stage):
    """Input function: every class's table of ``stage`` (``results/{stage}/{class_id}.parquet``).

    Each per-class stage writes one table per class as its declared output, with the
    class's per-interchange files (results/interchanges/{class_id}/{sample}/) beside.
    """

    def tables(wildcards):
        return [f"results/{stage}/{c}.parquet" for c in class_ids()]

    tables.__name__ = f"class_tables_{stage}"
    return tables


# -- geometry stage (workflow/rules/geometry.smk) --------------------------------
# 3: straight leads on climbing ramps (geometry.leads)
# 4: compiled DE generation step (other random trajectories), restarts 5
# 10: exact stretch tests in the conflict kernel, popsize 4, built C-D roads
# 11: an interchange with a ramp still in conflict is rebuilt with other seeds (rebuilds);
#     a child on the side of its parent facing a road attaches where it has room
# 12: one job per class; fitting seconds in results/geometry_timing/ (geometry.parquet
#     is the same bytes in every run)
# 13: radius held over 10 m (HOLD_M), attachment windows bounded by what a ramp needs
#     (length_margin), inf resampled only where sampling allows it
# 14: a ramp attached to a ramp attaches where its parent is level (no grade jump), if it can
# 15: expressways ending here (half lines) spread round the centre, on the level above the
#     through ones; windows stay on carriageways that begin or end here (catalog unchanged)
# 16: a ramp meeting itself at its level is a conflict (the search tests loops, the recount every ramp)
# 17: a ramp leaving / joining a ramp on a grade starts / ends at that grade (no kink); held to
#     where its parent is no steeper than its slope target when no level part is in its window
# 18: a stub whose child goes round a loop ends where it can; the loop keeps off that child's turn
# 19: a left turn between two expressways ending here (a 5-leg's) crests over every other
#     planned crest (catalog unchanged)
# 20: a collector road of split stubs whose loop goes to the road it crosses (Columbus
#     09) passes under it, ends past it beside its own road, level after its first stub
#     (a level ramp, never lifted); catalog unchanged
# 21: a ramp merging along a stub's body (not at its free start) adds a lane beside it, as
#     the writer's lane links do (Columbus r5 into r13 was laid over r13's outer lane)
# 22: a ramp's lane centre is nowhere (pointwise) tighter than 95 % of its radius target
#     (the search: 95.5 %); before, only the radius held over 10 m was (short end legs and
#     joints turned at down to a tenth of it)
# 23: the two branches of a T's terminal (straight on and right at the end; the merge
#     of the other carriageway likewise) are fenced off each other's side of the
#     carriageway's right edge until they are a clearance apart in height
#     (flyover.geometry.terminals): directional_t's rR no longer meets rL there; and a
#     ramp whose child attaches on the side facing its road keeps a lane off that road's
#     edge outside its window (flyover.geometry.beside): J1's r2 finds room beside r1/r3
# 24: an outer connector reaching its loop's roads through stubs (Columbus r11 round r6) is
#     fitted after the loop and round it; a collector road's level second stub (r13) before
#     the connector forking beside it (r2); catalog unchanged
# 25: expressways ending here that continue one another (DC 26's I-66 and Potomac Freeway)
#     are one line: the one without ramps to a third road runs on past the centre, in the
#     other's median, to 40 m short of its terminal; the ramps between them are short and
#     level (catalog unchanged: no design has such a pair)
# 26: a four-level stack's left turns between stub ends: those fitted first stay at their
#     planned level (not lifted) and clear of where the later ones climb from their fixed
#     ends, if they can (approaches.py); other designs unchanged
# 27: a road's attachment windows keep gap_m from where ramps fitted before attach to it
#     (any side or order), and ramps other than a continuation keep gap_m beyond its fixed
#     window by the road's end (DC 26 drawn set 0: r3 ended 0.45 m from r14 on I-66 North,
#     not exportable); catalog unchanged
# 28: resampling keeps an outer connector wider than its loop (the rule sampling keeps)
# 29: a T's terminal keeps climb room at the lowest slope of the ramps between that
#     expressway and a road on another level, or flying over between two on its level, not
#     of every ramp (DC 26 drawn sets 0 and 3: I-66's terminal 836 -> 511 m out, the E
#     Street Expressway's 853 -> 528 m); catalog unchanged (a T's ramps all climb between
#     its two expressways)
# 30: a ramp is no longer than max_length_ratio x the least it needs (its plan between its
#     windows at 0.95 x its radius, its turn, its climb to its crest and down) and two tapers:
#     the search is penalised beyond it and a fit over it is not ok (resampled or recorded
#     "length ... over bound ..."); the 5-8.7 km flyovers of 1 % slope targets no longer wander
# 31: a build the dense check (same_level_conflicts, as validation's clearance check) finds
#     a ramp at another's level in is built again with other seeds, as one whose fits count a
#     conflict (turbine workflow sample 6 at 30: lB1 1.3 m above B1 where it leaves eB1)
# 32: an outer connector attaches to a road it shares with its loop where, turning to 45
#     degrees at its radius and running straight on, it clears every point of the loop (a
#     lone arc of its radius left it inside the loop's far side: one in ten went over its
#     loop on the workflow's sets; cloverleaf 89.4 -> 100 % round, cloverstack 87.9 -> 95.5 %,
#     parclos 89.6 -> 100 %); cloverleaf_cd's connectors and loops, between C-D roads, are
#     pairs too (chains.Movements.through_stubs): each connector fitted after its loop and
#     round it if it can, resampled wider than it; on a C-D road a loop attaches within
#     stub_window_m beyond the crossing's room and its connector where it clears it (45
#     degrees): cloverleaf_cd (regenerated sets) 51.6 -> 85.5 % round
# 33: the last restart of a ramp between two windows starts from the shortest Dubins path
#     between them at its radius target, cut into Bézier pieces at its arcs' ends
#     (flyover.geometry.guess), and of two missing restarts the one within its radius is kept
#     (turbine's right turns merging 1-2 km out beyond the left turn: first try 893 -> 898/912;
#     33, not 32: main's 32 is issue33round's, merged after this branch left 0af5f78)
# 34: each end of a collector-distributor road where an outer connector leaves (joins) it
#     round a loop attached to it runs straight as far from the crossing as that connector
#     needs to go round the loop at 45 degrees (levels.LevelPlan.collector_room; before,
#     both ends twice its widest ramp's radius: a 280 m connector could not leave it beyond
#     a 210 m loop and went over it, a narrow pair had ~1 km): cloverleaf_cd 85.5 -> 99.2 %
#     round, C-D road median 1,928 -> 1,604 m; other designs unchanged (no C-D road)
# 35: the first of a stub's two children out of its fork (into its join) keeps clear of the
#     way its sibling needs, turning at its radius target until the two are a clearance
#     apart in height (flyover.geometry.fork; turbine's left turns swung right across their
#     sibling right turn's start: first try 898 -> 903/912, stack4 1,512 -> 1,518/1,536)
# 36: a stub carries all its children's lanes (Columbus's r8: 3, for r2 and the 2-lane
#     collector r13; its r2 lay on one of r13's lanes); a stub whose child is the outer
#     connector of a loop through stubs (Columbus's r1, r11 round r6) is fitted after that
#     loop and keeps out of where its child turns round it (loop_room.connector_fences),
#     and that connector leaves (joins) its road where it goes round the loop
#     (rails.road_rail) and keeps the child-room fence (beside.child_room_fences, out to a
#     child's far end at a fitted stub's free end: r12 from r13); Columbus, 8 drawn sets:
#     first try 94 -> 105/112, infeasible 8 -> 0 (with SAMPLING 7); catalog unchanged
# 37 (session 36's merges, one number):
#   - a stub's free end keeps half the climb of a child running to another stub's free end
#     without a crest (free_end.FreeEnds.connector_room: Columbus's r2 at 1 %; of the
#     catalog only stack4's right turns)
#   - a climb from a slight grade shortens its vertical curves by the share of the rise it
#     climbs itself (profile._leg_transition: cloverstack 20 oA1, 38 oA2 reach 3 %)
#   - a T whose ramps all run to one pair's line (DC's E Street Expressway, to I-66 /
#     Potomac Freeway) meets it square at a junction of its own beyond the line's terminal
#     (roads.tee_junctions), and the ramps between them keep their room from that junction
#     (rails.crossing_s), where it took the first free diagonal at the centre; left turns
#     into it fly a level above those leaving it (levels); a ramp joining on the left is no
#     loop (chains: DC's r8, r13); a continuation's ramp neither orders nor is ordered by
#     pos (rails: DC's r4); only DC's file 26 changes (layout_roads identical on the catalog
#     and the other extracts)
# 38: the resampler (tables.DomainResampler) draws only what sampling allows the class
#     (feasibility.sampling_model: the same forbidden and fixed features, with the sample's
#     lanes): DC's r3 / r4 no radius their shift cannot hold, the Ts' rL no 1 % slope; the
#     catalog's workflow sets never resample those ramps (geometry_bytes 3 identical)
#     and a stub with a collector road among its children keeps no connector room (Columbus's
#     r8: with half r2's climb its end lay 644 m out, r13's loop r6 beside I-70 and r1
#     4 m off I-70 West; free_end.FreeEnds.connector_room); the catalog has no such stub
#     (geometry_bytes unchanged);
#     one reading of an inf radius target (flyover.geometry.straight):
#     the fit, like the benchmark, holds it to 0.95 x inf_reference_m (250 m), not 0.95 x
#     30 m (geometry.inf_min_radius_m, removed); a ramp joining its road whose child comes
#     straight on from a fitted stub's free end runs beside the road a lane off its edge
#     before it merges, and the child joins it there (beside.beside_run, rails.straight_on:
#     Columbus's r11 and r12)
# 39: a split stub's free end slides clear of the road its chain runs beside also when
#     its parent ends right of that road's band but within the stub's margin (half its
#     width and 1 m): Columbus drawn set 15's r13 lay across I-270 (free_end.FreeEnds.
#     beside_road; the catalog has no stub splitting off a stub: geometry_bytes unchanged);
#     and a ramp running beside the road before a straight-on child joins reaches
#     its road's height first (RampSpec.end_z_first) and the child joins
#     it within that run (rails.RampWindows.beside_part): Columbus's r11 and r12
# 40: a connector between two stubs' free ends keeps off, first, where a loop fitted after
#     it leaves its road (state.LayoutState.loop_room; Columbus's r2 and the loop r5 at
#     I-70 East); a fenced miss is kept over an unfenced miss that ranks no better;
#     and a connector round its loop with a run beside its road for a straight-on child
#     is first held off the road's edge over the whole run (it runs straight there), then
#     in a slot twice as wide, then only over its first gap_m (both slots) as before, before
#     it drops the child's room (beside.run_slacks): Columbus's r11 and r12 (no catalog
#     design has a straight-on child)
# 41: the length that bounds how far out a ramp's end attaches to its road reads the climb
#     to a fitted parent ramp at the parent's height within the child's window there, not
#     the parent's mean height (RampSpecs.need_m; a stub's free end keeps its mean):
#     Columbus's r7 onto r3's plateau; of the catalog, trumpet changes (geometry_bytes 3:
#     trumpet 1 and 2); and a straight-on child's window on its parent takes in the
#     parent's whole run beside its road (rails.RampWindows.reach_run): Columbus's
#     r12 on r11 (no catalog design has a straight-on child); a connector keeping its
#     run beside its road for a straight-on child is lifted and restarted only in the
#     slot twice as wide to the run's end (and on the plain spec); in the other slots a
#     third seed instead
#     (build._round_fit: CPU only on 32 drawn Columbus sets, where those restarts never
#     met the fences; a set where one would have changes shape; no catalog design has a run);
#     a ramp whose fits all missed only by their slope (no conflict, shorter than its climb
#     at its slope target: every restart starts near the shortest path between its windows)
#     is searched again from detours about as long as its climb (build._detours: Dubins
#     paths through a waypoint, then random shapes long enough), no longer than twice its
#     climb; kept only if it meets its targets (Columbus's r2 at 1 %; catalog bytes
#     unchanged)
# 42: a child joining its parent straight on from a stub's free end that misses its
#     targets has its parent refitted with its run beside its road half, then all of the
#     child's radius farther along, kept only if both then meet their targets
#     (build._moved_run: Columbus's r12 into r11)
# 43: the road layout lays each ramp between two roads turning to the side its real one
#     turns to (the OSM reader's turn_deg), before the turn-side score (roads.layout_roads:
#     the Bangor cloverleaf was laid mirrored, its outer connectors as left flyovers;
#     Sydney, Portland Marquam and Boston I-93/US 1 change too); a ramp whose real one turns
#     right by over 180 deg is a loop even leaving before 0.4 (Bangor's r7); an outer
#     connector on a road its loop shares is fitted after the loop (state.order: Bangor's
#     r1-r4 came first by id); catalog bytes unchanged by these;
#     and a stub round its loop is not lifted nor restarted (build._round_fit; CPU: Columbus's
#     r1 round r6);
#     and a ramp joining (leaving) a fitted ramp along it, neither a loop nor straight-on,
#     attaches to its road within 1.5 x its turn and its climb to that ramp, one after
#     the other, not the longer of them (RampSpecs.need_m; Columbus's r7 onto r3; of the
#     catalog, trumpet changes in geometry_bytes 3)
# 44: a ramp that still misses its first try after rip-up and reroute is fitted again
#     without the fitted ramps that can move (those it meets; with none met, all), and
#     those its new curve meets are fitted again round it, kept only if all then meet
#     their targets (build._swapped: Columbus's r2 round the loop r5; stack4's lB2)
# 45: an outer connector round a loop that joins a collector road (Columbus's r2 round
#     r5, Movements.round_by_collector) is fitted after the loop and round it; the loop
#     joins the collector near the crossing (LoopRoom.near_crossing) and the stubs the
#     connector leaves and joins end beyond the loop's reach (LoopRoom.quadrant_fences)
# 46: an interchange whose outer connector goes over or under its loop is built again
#     with other seeds, as one with a same-level conflict (build.build_interchange; the
#     build with the fewest conflicts, then ramps missing targets or across their loop)
GEOMETRY_VERSION = 46


# -- throughput (step 6, workflow/rules/throughput.smk) ---------------------------------
# 1: first version (flows per topology movement, stable window from the balance of N(t))
THROUGHPUT_VERSION = 1


def throughput_class_series(wildcards):
    """Every class's entering/leaving time series."""
    return expand("results/throughput/{class_id}/series.parquet", class_id=class_ids())


# -- plugins (step 7, workflow/rules/plugins.smk) -----------------------------------------
# 1: first version (generic plugin step; truck_fuel 0.1.0)
PLUGINS_VERSION = 1


wildcard_constraints:
    plugin=r"[a-z][a-z0-9_]*",


def plugin_names():
    """The plugins the config asks for (keys of `plugins:`)."""
    return sorted(config.get("plugins") or {})


def plugin_version(wildcards):
    """The installed version of a plugin's distribution (metadata only, nothing imported)."""
    from flyover.plugins.registry import plugin_entry_points

    for info in plugin_entry_points():
        if info.name == wildcards.plugin:
            return info.distribution_version
    raise ValueError(f"plugin {wildcards.plugin!r} is configured but not installed "
                     f"(`flyover plugins` lists what is)")


def plugin_config(wildcards):
    """A plugin's config section (the plugin fills its defaults and validates it)."""
    return config["plugins"][wildcards.plugin] or {}


def plugin_class_tables(wildcards):
    """Every configured plugin's rows of every class."""
    return expand("results/plugins/{plugin}/{class_id}.parquet", plugin=plugin_names(),
                  class_id=class_ids())
