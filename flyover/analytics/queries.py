"""Named queries: the paper's tables and figures as SQL over the views.

``flyover query --named NAME`` runs one; ``flyover query --list`` lists them.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["NamedQuery", "NAMED_QUERIES"]


@dataclass(frozen=True)
class NamedQuery:
    """A query with a name, what it shows, and its SQL."""

    name: str
    description: str
    sql: str


_CLASS_NAMES = "(SELECT class_id, any_value(class_name) AS class_name FROM classes GROUP BY class_id)"

NAMED_QUERIES: dict[str, NamedQuery] = {q.name: q for q in (
    NamedQuery(
        "fuel-by-class",
        "truck fuel per class: ramps, share completed, median and mean ml/km, by direction "
        "(paper Fig. 7)",
        f"""
        SELECT f.class_id, n.class_name, f.direction,
               count(*) AS ramps,
               round(avg(f.completed::INT), 3) AS completed_share,
               round(median(f.fuel_ml_per_km) FILTER (WHERE f.completed), 1) AS median_ml_per_km,
               round(avg(f.fuel_ml_per_km) FILTER (WHERE f.completed), 1) AS mean_ml_per_km,
               round(avg(f.fuel_ml) FILTER (WHERE f.completed), 1) AS mean_ml_per_ramp
        FROM fuel f LEFT JOIN {_CLASS_NAMES} n USING (class_id)
        GROUP BY ALL ORDER BY n.class_name, f.direction
        """),
    NamedQuery(
        "fuel-totals",
        "truck fuel per class over all its ramps: ramps, ramp-km, litres, ml/km",
        f"""
        SELECT n.class_name, f.class_id, count(*) AS ramps,
               round(sum(f.length_m) / 1000, 1) AS ramp_km,
               round(sum(f.fuel_ml) / 1000, 2) AS litres,
               round(1000 * sum(f.fuel_ml) / sum(f.length_m)) AS ml_per_km
        FROM fuel f LEFT JOIN {_CLASS_NAMES} n USING (class_id)
        WHERE f.completed
        GROUP BY ALL ORDER BY ml_per_km DESC
        """),
    NamedQuery(
        "fuel-by-direction",
        "truck fuel over the whole catalog by ramp direction (up, level, down)",
        """
        SELECT direction, count(*) AS ramps,
               round(sum(length_m) / 1000, 1) AS ramp_km,
               round(median(fuel_ml_per_km), 1) AS median_ml_per_km,
               round(quantile_cont(fuel_ml_per_km, 0.95), 1) AS p95_ml_per_km,
               round(avg(mean_speed_mps), 2) AS mean_speed_mps,
               round(avg(completed::INT), 3) AS completed_share
        FROM fuel GROUP BY direction ORDER BY direction
        """),
    NamedQuery(
        "fuel-grid",
        "paper Table IV from the catalog: fuel by the ramps' target radius and slope "
        "(geometry's targets) and direction",
        """
        SELECT g.target_radius_m AS radius_m, g.target_slope_pct AS slope_pct, f.direction,
               count(*) AS ramps,
               round(avg(f.fuel_ml), 1) AS mean_ml_per_ramp,
               round(avg(f.fuel_ml_per_km), 1) AS mean_ml_per_km,
               round(avg(f.mean_speed_mps), 2) AS mean_speed_mps
        FROM fuel f JOIN geometry g
          ON g.class_id = f.class_id AND g.sample = f.sample AND g.ramp = f.ramp
        WHERE f.completed AND f.direction <> 'level'
        GROUP BY ALL ORDER BY f.direction DESC, radius_m, slope_pct
        """),
    NamedQuery(
        "fuel-incomplete",
        "ramps the truck could not drive within its limits, with the reason",
        """
        SELECT class_id, sample, ramp, round(min_radius_m, 1) AS min_radius_m,
               round(max_slope_pct, 2) AS max_slope_pct, reason
        FROM fuel WHERE NOT completed ORDER BY class_id, sample, ramp
        """),
    NamedQuery(
        "tracking",
        "truck tracking quality: lateral error and acceleration quantiles (ramps of radius >= 30 m)",
        """
        SELECT count(*) AS ramps,
               round(median(max_lateral_error_m), 3) AS median_max_error_m,
               round(quantile_cont(max_lateral_error_m, 0.95), 3) AS p95_max_error_m,
               round(max(max_lateral_error_m), 3) AS worst_error_m,
               round(max(max_lateral_accel_mps2), 2) AS worst_lateral_accel_mps2
        FROM fuel WHERE completed AND min_radius_m >= 30
        """),
    NamedQuery(
        "throughput-by-class",
        "stable throughput per class and density: mean, std, samples (paper Table II, Fig. 5)",
        f"""
        SELECT t.class_id, n.class_name, t.density_veh_h, count(*) AS samples,
               round(avg(t.throughput_veh_h), 1) AS mean_veh_h,
               round(stddev_samp(t.throughput_veh_h), 1) AS std_veh_h,
               sum(t.teleports) AS teleports, sum(t.collisions) AS collisions
        FROM throughput t LEFT JOIN {_CLASS_NAMES} n USING (class_id)
        GROUP BY ALL ORDER BY n.class_name, t.density_veh_h
        """),
    NamedQuery(
        "coverage",
        "t-way coverage per class (paper §III-C)",
        f"""
        SELECT c.class_id, n.class_name, c.t, c.n_params, c.rows, c.tuples_total,
               c.tuples_covered, c.lower_bound
        FROM coverage c LEFT JOIN {_CLASS_NAMES} n USING (class_id) ORDER BY n.class_name
        """),
    NamedQuery(
        "geometry-by-class",
        "ramps meeting their targets per class, and fitting time",
        f"""
        SELECT g.class_id, n.class_name, count(DISTINCT g.sample) AS interchanges,
               count(*) AS ramps, round(avg(g.ok::INT), 3) AS ok_share,
               round(median(g.length_m), 1) AS median_length_m,
               round(median(t.seconds), 2) AS median_seconds
        FROM geometry g LEFT JOIN geometry_timing t USING (class_id, sample, ramp)
             LEFT JOIN {_CLASS_NAMES} n USING (class_id)
        GROUP BY ALL ORDER BY n.class_name
        """),
    NamedQuery(
        "validation-summary",
        "share of interchanges passing each validation check",
        """
        SELECT "check", count(*) AS interchanges, round(avg(ok::INT), 3) AS ok_share
        FROM validation GROUP BY "check" ORDER BY "check"
        """),
)}
