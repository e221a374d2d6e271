"""The planner's answer: :class:`Plan`, for machines (``plan.json``) and for people (``plan.md``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["PLAN_ESTIMATE_DENSITY", "Plan"]

PLAN_ESTIMATE_DENSITY = 0.77
"""The paper's planning estimate: ``0.77 A / r**2`` nodes (the honeycomb's density)."""


@dataclass
class Plan:
    """The planner's answer (see the module docstring); :meth:`to_dict` for machines, :meth:`markdown` for people.

    Attributes:
        map: The map's name.
        bases: Base-station positions.
        r_c: Communication radius (m).
        agents_per_base: Agents per base station.
        area_m2: Reachable free area.
        estimate_nodes: ``ceil(0.77 A / r_c**2)``.
        patterns: Pattern name → ``{"placed", "estimated", "coverage", "connected"}`` on the map.
        runs: One dict per agent-assisted run: ``seed``, ``status``, ``routers_deployed``, ``nodes_total``,
            ``coverage``, ``stop_reason``, ``sim_time_s``, ``agents_connected_min``, ``error``.
        confidence: The quantile the recommendation is taken at.
        distribution: ``runs``, ``completed``, ``min``, ``median``, ``mean``, ``quantile``, ``max`` of routers
            deployed over the completed runs.
        recommended: Routers to carry (``None`` when no run reached the coverage target).
        typical_seed: Seed of the completed run closest to the median (the picture's run).
        warnings: Lines the user must read (incomplete or failed runs).
        settings: Explorer, time limit, coverage target, seeds.
    """

    map: str
    bases: list[tuple[float, float]]
    r_c: float
    agents_per_base: int
    area_m2: float
    estimate_nodes: int
    patterns: dict[str, dict[str, Any]]
    runs: list[dict[str, Any]]
    confidence: float
    distribution: dict[str, Any]
    recommended: int | None
    typical_seed: int | None
    warnings: list[str] = field(default_factory=list)
    settings: dict[str, Any] = field(default_factory=dict)
    connected: dict[str, Any] = field(default_factory=dict)
    """Time the agents were connected over the finished runs
    (:func:`~amronet.planning.planner.connected_distribution`)."""
    scenario: dict[str, Any] = field(default_factory=dict, repr=False)
    optimum: dict[str, Any] | None = None
    """``amronet plan --optimum``: the best placement on a lattice and its proven bound (:mod:`amronet.optimum`)."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible content of ``plan.json``."""
        n_b = len(self.bases)
        return {
            "map": self.map, "bases": [list(b) for b in self.bases], "r_c": self.r_c,
            "agents_per_base": self.agents_per_base, "reachable_area_m2": self.area_m2,
            "estimate_077": {"nodes": self.estimate_nodes, "routers_to_carry": max(0, self.estimate_nodes - n_b)},
            "patterns": {k: {**v, "routers_to_carry": max(0, v["placed"] - n_b)} for k, v in self.patterns.items()},
            "agent_assisted": {"distribution": self.distribution, "runs": self.runs},
            "confidence": self.confidence, "recommended_routers": self.recommended, "typical_seed": self.typical_seed,
            "connected": self.connected,
            "warnings": self.warnings, "settings": self.settings, "scenario": self.scenario,
            **({"optimum": self.optimum} if self.optimum is not None else {}),
        }  # fmt: skip

    def markdown(self, picture: str | None = "typical.png") -> str:
        """``plan.md``: the inputs, the three answers in one table, the distribution and the recommendation."""
        n_b, d = len(self.bases), self.distribution
        q = f"{100 * self.confidence:g}th percentile"
        bases = ", ".join(f"({x:g}, {y:g})" for x, y in self.bases)
        lines = [f"# Deployment plan: {self.map}", "",
                 f"Base stations {bases}; r_c = {self.r_c:g} m; {self.agents_per_base} agent(s) per base station; "
                 f"reachable free area {self.area_m2:.1f} m².", ""]
        st = self.settings
        if st.get("radio") is not None:
            stock = "unlimited" if st.get("stock") is None else f"{st['stock']} per agent ({st.get('when_empty')})"
            radio = ", ".join(f"{k} {v}" for k, v in st["radio"].items())
            lines += [f"Radio: {radio}; drop rule {st.get('drop_rule')}; stock {stock}.", ""]
        if self.recommended is not None:
            if st.get("trajectories") is not None:
                which = f"that followed the paths of {st['trajectories']}"
            elif st.get("stock") is not None:
                which = "that finished (with a stock every finished run counts)"
            else:
                which = f"that reached {100 * st['coverage_target']:g} % coverage"
            lines += [f"**Carry {self.recommended} routers** (the {q} of {d['completed']} agent-assisted runs "
                      f"{which}, rounded up).", ""]
        else:
            lines += ["**No recommendation**: no agent-assisted run reached the coverage target.", ""]
        lines += ["| method | nodes (incl. base nodes) | routers to carry |", "|---|---:|---:|",
                  f"| 0.77·A/r² (paper's estimate) | {self.estimate_nodes} | {max(0, self.estimate_nodes - n_b)} |"]
        for name, p in self.patterns.items():
            conn = "" if p["connected"] else ", not connected"
            lines.append(f"| {name} placed on the map (estimated {p['estimated']}{conn}) | {p['placed']} | "
                         f"{max(0, p['placed'] - n_b)} |")
        o = self.optimum
        if o is not None:
            state = "optimal" if o["optimal"] else f"proven bound {o['lower_bound']}"
            lines.append(f"| fewest on a {o['spacing_m']:g} m lattice (amronet optimum, {state}) | "
                         f"{o['routers'] + n_b} | {o['routers']} |")
        if d["completed"]:
            for label, key in (("minimum", "min"), ("median", "median"), ("mean", "mean"), (q, "quantile"),
                               ("maximum", "max")):
                value = d[key]
                shown = f"{value:.1f}" if isinstance(value, float) and not float(value).is_integer() else f"{value:g}"
                lines.append(f"| agent-assisted deployment, {label} | {float(value) + n_b:g} | {shown} |")
        counted = (f"{d.get('reached_target', d['completed'])} reached the target"
                   + ("; with a stock every finished run counts" if self.settings.get("stock") is not None else "")
                   + ("; on given paths every finished run counts" if st.get("trajectories") is not None else ""))
        lines += ["", f"Agent-assisted runs: {d['runs']} ({counted}), "
                      f"explorer {self.settings['explorer']}, time limit {self.settings['time_limit']:g} s, "
                      f"seeds {self.settings['seeds'][0]}..{self.settings['seeds'][-1]}."]
        c = self.connected
        if c.get("runs") and "median" in c:
            lines += ["", f"Time the agents were connected to a base station over {c['runs']} runs (agents cut off at "
                          f"least once in {c['cut_off_runs']}):", "", "| min | pessimistic | median | mean | max |",
                      "|---:|---:|---:|---:|---:|",
                      f"| {100 * c['min']:.1f} % | {100 * c['quantile']:.1f} % | {100 * c['median']:.1f} % | "
                      f"{100 * c['mean']:.1f} % | {100 * c['max']:.1f} % |"]
        if o is not None and self.recommended is not None and o["routers"] > 0:
            lines += ["", f"The recommendation is {self.recommended / o['routers']:.2f} times the best placement "
                          f"found on the lattice ({o['routers']} routers, covering all of the reachable space) and at "
                          f"most {self.recommended / max(o['lower_bound'], 1):.2f} times the fewest the lattice allows "
                          f"(at least {o['lower_bound']}); runs stop at their coverage target."]
        if "per_agent" in d:
            lines += ["", f"Per agent: {d['per_agent']} routers."]
        if self.warnings:
            lines += ["", *(f"- warning: {w}" for w in self.warnings)]
        if picture and self.typical_seed is not None:
            lines += ["", f"![a typical deployment (seed {self.typical_seed})]({picture})"]
        return "\n".join(lines) + "\n"
