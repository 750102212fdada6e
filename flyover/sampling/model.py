"""The feature model of a topology: its parameters, their domains, forbidden combinations.

A **regulation profile** (config ``sampling.profiles.<name>``) gives, per node
kind, the features to sample and their values, and the combinations design
rules forbid. The paper's profile (FLYOVER §III-C, from China's interchange
design rules) is the default ``china``::

    china:
      road: {lanes: [3, 4, 5]}
      ramp: {radius_m: [.inf, 280, 210, 150, 100, 60, 40, 30], slope_pct: [1, 2, 3, 4, 5]}
      forbid:
        # on one element: no 30-40 m loop on a 5 % grade
        - elements: [{kind: ramp, radius_m: [30, 40], slope_pct: 5}]
        # across two elements joined by an edge (first -> second, direction of travel)
        - where: connected
          elements: [{kind: road, lanes: 5}, {kind: ramp, radius_m: 30}]

A rule with one element applies to every element of that kind; with two, to
every ordered pair of distinct elements of those kinds, joined by an edge
(``where: connected``, the default) or not (``where: any``). An element may
also name one node (``{kind: ramp, element: r3, ...}``), as a later stage
does when it finds a combination infeasible for one class (``extra`` of
:func:`feature_model`).

For a topology, every (element, feature) is one parameter of the covering
array, roads first, then ramps, each in id order, except **fixed** features:
a value a later stage imposes whatever the sample (``fixed`` of
:func:`feature_model`; e.g. slope 0 on a level ramp, see
:mod:`flyover.geometry.feasibility`). A fixed feature is no column of the
array (coverage counts only the real parameters) and its value is written
into every feature row. A forbidden combination that names a fixed feature
applies where the fixed value is among its values (and then constrains the
rest of the combination), never where it is not.

Examples
--------
>>> from flyover.topology.catalog import catalog_topologies
>>> model = feature_model(catalog_topologies()["j1"], default_profile())
>>> len(model.parameters), model.levels[:5]
(12, (3, 3, 3, 3, 8))
>>> fixed = feature_model(catalog_topologies()["j1"], default_profile(),
...                       fixed={("r1", Feature.SLOPE_PCT): 0.0})
>>> len(fixed.parameters), fixed.value("r1", Feature.SLOPE_PCT)
(11, 0.0)
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from flyover.errors import ConfigError
from flyover.sampling.constraints import Forbidden
from flyover.topology.model import Kind, Topology

__all__ = ["Feature", "Relation", "ElementCondition", "ForbidRule", "Profile", "Parameter",
           "FeatureModel", "feature_model", "profile_from_dict", "profile_from_config",
           "default_profile", "DEFAULT_PROFILE"]


class Feature(str, enum.Enum):
    """A geometric feature; the value is its column in ``features/{class_id}.parquet``."""

    LANES = "lanes"
    RADIUS_M = "radius_m"
    SLOPE_PCT = "slope_pct"


class Relation(str, enum.Enum):
    """How the two elements of a forbidden combination relate."""

    CONNECTED = "connected"  # an edge first -> second
    ANY = "any"              # any two distinct elements


@dataclass(frozen=True)
class ElementCondition:
    """One element of a forbidden combination: its kind, optionally its id, and the
    values it must hold."""

    kind: Kind
    values: tuple[tuple[Feature, frozenset[float]], ...]
    element: str | None = None


@dataclass(frozen=True)
class ForbidRule:
    """A forbidden combination of feature values on one element or two related ones."""

    elements: tuple[ElementCondition, ...]
    where: Relation = Relation.CONNECTED


@dataclass(frozen=True)
class Profile:
    """A regulation profile: per kind, the sampled features and their values; forbidden rules."""

    name: str
    domains: tuple[tuple[Kind, tuple[tuple[Feature, tuple[float, ...]], ...]], ...]
    forbid: tuple[ForbidRule, ...] = ()

    def domain(self, kind: Kind) -> dict[Feature, tuple[float, ...]]:
        """Feature → values for elements of ``kind`` (empty if it samples none)."""
        return dict(dict(self.domains).get(kind, ()))


@dataclass(frozen=True)
class Parameter:
    """One column of the covering array: a feature of one element and its values."""

    element: str
    kind: Kind
    feature: Feature
    values: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class FeatureModel:
    """The parameters of one topology under a profile, the forbidden combinations and the
    fixed features (``(element, feature, value)``, not parameters: the same in every row)."""

    topology: Topology
    profile: Profile
    parameters: tuple[Parameter, ...]
    forbidden: tuple[Forbidden, ...]
    fixed: tuple[tuple[str, Feature, float], ...] = ()

    @property
    def levels(self) -> tuple[int, ...]:
        return tuple(len(p.values) for p in self.parameters)

    def value(self, element: str, feature: Feature) -> float | None:
        """The fixed value of ``element``'s ``feature`` (``None`` if it is not fixed)."""
        return next((v for e, f, v in self.fixed if e == element and f is feature), None)

    def elements(self) -> list[tuple[str, Kind]]:
        """Every road, then every ramp, in id order."""
        t = self.topology
        return [(r, Kind.ROAD) for r in t.roads] + [(r, Kind.RAMP) for r in t.ramps]


#: the paper's domains (FLYOVER §III-C, from China's interchange design rules)
DEFAULT_PROFILE: dict[str, Any] = {
    "road": {"lanes": [3, 4, 5]},
    "ramp": {"radius_m": [math.inf, 280, 210, 150, 100, 60, 40, 30], "slope_pct": [1, 2, 3, 4, 5]},
    "forbid": [],
}


def _number(value: Any, where: str, source: str | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        if isinstance(value, str) and value.strip().lower() in ("inf", ".inf", "infinity"):
            return math.inf
        raise ConfigError(f"expected a number, got {value!r}", source=source, element=where)
    return float(value)


def profile_from_dict(name: str, doc: Mapping[str, Any], source: str | None = None) -> Profile:
    """Build a :class:`Profile` from its config mapping (format in the module docstring).

    Raises
    ------
    ConfigError
        Naming the key at fault: unknown kind or feature, a repeated value, a
        forbidden value outside the domain, a rule of more than two elements.
    """
    at = f"sampling.profiles.{name}"
    domains = []
    for kind in Kind:
        features = doc.get(kind.value) or {}
        entries = []
        for fname, values in features.items():
            where = f"{at}.{kind.value}.{fname}"
            try:
                feature = Feature(fname)
            except ValueError:
                raise ConfigError(f"unknown feature (expected one of {', '.join(f.value for f in Feature)})",
                                  source=source, element=where) from None
            vals = tuple(_number(v, where, source) for v in values)
            if not vals or len(set(vals)) != len(vals):
                raise ConfigError("a domain needs distinct values", source=source, element=where)
            entries.append((feature, vals))
        if entries:
            domains.append((kind, tuple(entries)))
    unknown = set(doc) - {k.value for k in Kind} - {"forbid", "description"}
    if unknown:
        raise ConfigError(f"unknown key(s) {', '.join(sorted(unknown))}", source=source, element=at)
    if not domains:
        raise ConfigError("a profile needs at least one feature", source=source, element=at)
    profile = Profile(name, tuple(domains))
    rules = tuple(_rule(r, profile, f"{at}.forbid[{i}]", source) for i, r in enumerate(doc.get("forbid") or []))
    return Profile(name, tuple(domains), rules)


def _rule(doc: Any, profile: Profile, at: str, source: str | None) -> ForbidRule:
    if not isinstance(doc, Mapping) or not isinstance(doc.get("elements"), list):
        raise ConfigError("a forbidden combination is {elements: [...], where: connected|any}",
                          source=source, element=at)
    items = doc["elements"]
    if not 1 <= len(items) <= 2:
        raise ConfigError("a forbidden combination names one or two elements", source=source, element=at)
    try:
        where = Relation(doc.get("where", Relation.CONNECTED.value))
    except ValueError:
        raise ConfigError("where must be connected or any", source=source, element=f"{at}.where") from None
    conds = []
    for j, item in enumerate(items):
        el = f"{at}.elements[{j}]"
        try:
            kind = Kind(item.get("kind"))
        except (AttributeError, ValueError):
            raise ConfigError("each element needs kind: road or ramp", source=source, element=el) from None
        domain = profile.domain(kind)
        values = []
        for fname, vs in item.items():
            if fname in ("kind", "element"):
                continue
            try:
                feature = Feature(fname)
            except ValueError:
                raise ConfigError(f"unknown feature {fname!r}", source=source, element=el) from None
            if feature not in domain:
                raise ConfigError(f"profile {profile.name} samples no {fname} for a {kind.value}",
                                  source=source, element=f"{el}.{fname}")
            chosen = frozenset(_number(v, f"{el}.{fname}", source) for v in (vs if isinstance(vs, list) else [vs]))
            outside = sorted(chosen - set(domain[feature]))
            if outside:
                raise ConfigError(f"value(s) {', '.join(map(str, outside))} not in the {fname} domain",
                                  source=source, element=f"{el}.{fname}")
            values.append((feature, chosen))
        if not values:
            raise ConfigError("an element needs at least one feature value", source=source, element=el)
        name = item.get("element")
        conds.append(ElementCondition(kind, tuple(sorted(values)), None if name is None else str(name)))
    return ForbidRule(tuple(conds), where)


def default_profile() -> Profile:
    """The paper's profile (``china``)."""
    return profile_from_dict("china", DEFAULT_PROFILE)


def profile_from_config(config: Mapping[str, Any], name: str | None = None,
                        source: str | None = None) -> Profile:
    """The profile ``name`` (default: ``sampling.profile``) of a validated config."""
    sampling = config.get("sampling") or {}
    name = name or sampling.get("profile", "china")
    profiles = sampling.get("profiles") or {}
    if name not in profiles:
        if name == "china":
            return default_profile()
        raise ConfigError(f"unknown profile {name!r} (known: {', '.join(sorted(profiles)) or 'none'})",
                          source=source, element="sampling.profile")
    return profile_from_dict(name, profiles[name], source)


def feature_model(topology: Topology, profile: Profile, extra: Iterable[ForbidRule] = (),
                  fixed: Mapping[tuple[str, Feature], float] | None = None) -> FeatureModel:
    """The parameters of ``topology`` under ``profile``.

    Parameters
    ----------
    topology
        The class's topology.
    profile
        Domains and forbidden combinations.
    extra
        More forbidden combinations (e.g. ones a later stage found infeasible).
    fixed
        ``(element, feature) → value`` held constant instead of sampled (e.g.
        :func:`flyover.geometry.feasibility.fixed_features`); the value need
        not be in the profile's domain.

    Raises
    ------
    ConfigError
        A fixed feature names an element that is not in the topology, or its
        value is forbidden outright by a combination of fixed values.
    """
    model = FeatureModel(topology, profile, (), ())
    kinds = dict(model.elements())
    pinned: dict[tuple[str, Feature], float] = {}
    for (element, feature), value in (fixed or {}).items():
        if element not in kinds:
            raise ConfigError("fixed feature of an element not in the topology",
                              source=topology.source, element=element)
        pinned[element, Feature(feature)] = float(value)
    pinned = dict(sorted(pinned.items(), key=lambda kv: (kv[0][0], kv[0][1].value)))
    params, index = [], {}
    for element, kind in model.elements():
        for feature, values in profile.domain(kind).items():
            if (element, feature) not in pinned:
                index[element, feature] = len(params)
                params.append(Parameter(element, kind, feature, values))
    forbidden = []
    for rule in (*profile.forbid, *extra):
        for elements in _matches(topology, model.elements(), rule):
            cells: dict[int, set[int]] = {}
            applies = True
            for element, cond in zip(elements, rule.elements):
                for feature, chosen in cond.values:
                    if (element, feature) in pinned:
                        applies = applies and pinned[element, feature] in chosen
                        continue
                    p = index[element, feature]
                    cells[p] = {i for i, v in enumerate(params[p].values) if v in chosen}
            if not applies or not all(cells.values()):
                continue  # can never hold: a fixed or a domain value outside the combination
            if not cells:
                raise ConfigError(f"fixed values of {', '.join(elements)} are a forbidden combination",
                                  source=topology.source, element=", ".join(elements))
            forbidden.append(Forbidden.of(cells))
    return FeatureModel(topology, profile, tuple(params), tuple(dict.fromkeys(forbidden)),
                        tuple((e, f, v) for (e, f), v in pinned.items()))


def _matches(topology: Topology, elements: list[tuple[str, Kind]], rule: ForbidRule):
    """The element tuples a rule applies to."""
    def fits(cond: ElementCondition) -> list[str]:
        return [e for e, k in elements if k is cond.kind and cond.element in (None, e)]

    first = fits(rule.elements[0])
    if len(rule.elements) == 1:
        yield from ((e,) for e in first)
        return
    second = fits(rule.elements[1])
    for a in first:
        for b in second:
            if a != b and (rule.where is Relation.ANY or topology.graph.has_edge(a, b)):
                yield a, b
