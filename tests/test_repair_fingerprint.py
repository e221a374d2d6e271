"""The repair rules' runs stay what they were: summary, time series, network and positions after a fault, bit for bit.

SHA-256 of a short ``reproduce failures`` run (routers fail at 100 s, the run goes on to 250 s) of each repair rule,
``relocate`` and ``retrace``, on ``office-32x32`` and ``hospital_section`` under the unit disk and the multi-wall
radio with shadowing. The digests were taken before the repair rules' per-step bookkeeping was vectorised; a change
that starts, steers or stops one relocation differently, or moves any robot by one bit, changes them. Like the
golden fingerprints they hold with numpy at AVX2 at most (``make test`` sets ``NPY_DISABLE_CPU_FEATURES``).
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

import amronet
from amronet.algorithms.agent_assisted import relocate
from amronet.engine.network import connected_to
from amronet.experiments.failures import _scenario

FAULT_AT = 100.0
AFTER = 150.0
FRACTION = 0.3
SEED = 5

FINGERPRINTS = {
    ("agent-assisted-relocate", "office-32x32", "unit-disk"):
        "a613972b613f8f9dfe6da18e24f8cddb92ac35fd79c9ae5da6d764c3caf0ed0b",
    ("agent-assisted-retrace", "office-32x32", "unit-disk"):
        "04f69f0d7ccca7d4871b7e9293c709924a5333a8b74f07e263fa6540a30358cd",
    ("agent-assisted-relocate", "office-32x32", "multi-wall-shadowing"):
        "f2a151c401080683b994ea090965da0ad43ba8d1c415e3ee6f3d60b3ec5dd178",
    ("agent-assisted-retrace", "office-32x32", "multi-wall-shadowing"):
        "24f101e0da9903482337d766bd34ef65bcb1f62b7c1415115c5fbb3aba09493a",
    ("agent-assisted-relocate", "hospital_section", "unit-disk"):
        "3d5f9c356ed48b04645b7e23e694690a0b6f96991b80ee101f232cf5386480b2",
    ("agent-assisted-retrace", "hospital_section", "unit-disk"):
        "0b8dd8cc172aff363df18d0cfac0811911d6cc05a62c4a346298f99a9f877961",
    ("agent-assisted-relocate", "hospital_section", "multi-wall-shadowing"):
        "9c85b2eacbfff481f18eb12d6d2072090e475b1851930a4add3ec5ecb829c897",
    ("agent-assisted-retrace", "hospital_section", "multi-wall-shadowing"):
        "283e1ab47c0c89cacfbd109f2b30336860debffd6e1ca3518cbc31a39e295c1e",
}


def _feed(h, value) -> None:
    a = np.ascontiguousarray(value)
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())


def fingerprint(algorithm: str, map_name: str, radio: str) -> tuple[str, dict]:
    """The run's digest and its mission report (which says how many relocations it started)."""
    res = amronet.run(_scenario(algorithm, map_name, FRACTION, FAULT_AT, AFTER, "frontier", radio), seed=SEED)
    summary = {k: v for k, v in res.summary.items() if k not in ("wall_time_s", "amronet_version")}
    h = hashlib.sha256()
    h.update(json.dumps(summary, sort_keys=True, default=repr).encode())
    for name in sorted(res.timeseries):
        h.update(name.encode())
        _feed(h, res.timeseries[name])
    h.update(json.dumps(res.network, sort_keys=True).encode())
    sw = res.run.swarm
    for array in (sw.xy, sw.heading, sw.state, sw.distance):
        _feed(h, array)
    return h.hexdigest(), res.summary["mission"]


@pytest.mark.parametrize(("algorithm", "map_name", "radio"), sorted(FINGERPRINTS))
def test_repair_runs_keep_their_fingerprint(algorithm, map_name, radio):
    digest, mission = fingerprint(algorithm, map_name, radio)
    assert mission["relocations"] >= 2  # (the repair acted: the fingerprint covers its moves)
    assert digest == FINGERPRINTS[(algorithm, map_name, radio)]


@pytest.mark.parametrize("algorithm", ["agent-assisted-relocate", "agent-assisted-retrace"])
def test_the_repair_looks_for_cut_off_routers_only_when_the_network_changed(monkeypatch, algorithm):
    """Losses that stay due (a router still connected, one that cannot move) do not search the network every step."""
    calls = []

    def counted(*args, **kwargs):
        calls.append(1)
        return connected_to(*args, **kwargs)

    monkeypatch.setattr(relocate, "connected_to", counted)
    res = amronet.run(_scenario(algorithm, "office-32x32", FRACTION, FAULT_AT, AFTER, "frontier", "unit-disk"),
                      seed=SEED)
    assert res.summary["mission"]["relocations"] >= 2
    assert 0 < len(calls) < res.summary["steps"] / 20  # (each step once or twice before: 1 020 and 854 searches)
