"""The sampling section of the workflow configuration, as values."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Mapping

from flyover.sampling.covering import SearchBudget
from flyover.sampling.model import Profile, profile_from_config

__all__ = ["SamplingSettings", "settings_from_config"]


@dataclass(frozen=True)
class SamplingSettings:
    """Strength, regulation profile and search effort of the sampling stage."""

    t: int
    profile: Profile
    budget: SearchBudget


def settings_from_config(config: Mapping[str, Any], *, profile: str | None = None,
                         t: int | None = None, source: str | None = None) -> SamplingSettings:
    """Settings from a config's ``sampling`` section, with optional overrides.

    Examples
    --------
    >>> s = settings_from_config({"sampling": {"t": 3}})
    >>> s.t, s.profile.name
    (3, 'china')
    """
    section = config.get("sampling") or {}
    budget = SearchBudget()
    if "work" in section:
        budget = replace(budget, work=int(section["work"]))
    return SamplingSettings(t=int(t or section.get("t", 2)),
                            profile=profile_from_config(config, profile, source), budget=budget)
