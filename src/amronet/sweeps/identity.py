"""The identity of a run: the fully resolved scenario as canonical JSON, and its hash.

Two runs are the same run when their resolved scenarios and seeds are equal. *Resolved* means: the validated
:class:`~amronet.scenario.Scenario` dumped to plain data, with the algorithm's parameters replaced by the
algorithm's own validated parameter model (so defaults are spelt out: ``{}`` and ``{triangular: local}`` are
the same run for self-spreading), and a map (and an agents' trajectory file) given as a file path made absolute (so
the same relative path seen from two folders is not taken for one map, and a worker on another machine of a shared
file system finds it).
*Canonical JSON* sorts keys and drops whitespace; the hash is the SHA-256 of it together with a digest of the
map's *content* (:func:`map_digest`: the map YAML's bytes and the bytes of the image it names, for built-in maps
the files shipped in ``amronet/data/maps``), so editing a map file in place makes its runs new runs instead of
silently reusing the old ones. The digests are cached per file path, modification time and size. Only the
parent process computes hashes (workers get the resolved scenario), so the key never differs between a local
pool and a Dask cluster.

Example:
    >>> from amronet.scenario import load_scenario
    >>> a = resolve_scenario(load_scenario("self-spreading-6x6"))
    >>> b = resolve_scenario(load_scenario("self-spreading-6x6", {"algorithm.params": {}}))
    >>> scenario_hash(a) == scenario_hash(b)
    True
"""

from __future__ import annotations

import functools
import hashlib
import json
import stat
from importlib import resources
from pathlib import Path
from typing import Any

from amronet.errors import MapError, ScenarioError
from amronet.scenario import Scenario
from amronet.world.builtin import BUILTIN_MAPS
from amronet.yaml_loading import load_yaml

__all__ = ["canonical_json", "map_digest", "resolve_scenario", "scenario_hash"]

_MISSING = "missing"


def canonical_json(data: Any) -> str:
    """Plain data as canonical JSON: keys sorted, no whitespace, UTF-8 kept as is."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def _resolved_map(scenario: Scenario) -> str:

    ref = scenario.map
    if ref in BUILTIN_MAPS:
        return ref
    path = Path(ref)
    looks_like_path = ref.endswith((".yaml", ".yml")) or "/" in ref
    if not looks_like_path and not path.is_file():
        raise MapError("map", f"{ref!r} is neither a built-in map name ({', '.join(BUILTIN_MAPS)}; amronet maps "
                              "list) nor a map file; give one of those names or the path of a ROS map_server YAML")
    if looks_like_path and scenario.base_dir and not path.is_absolute():
        path = Path(scenario.base_dir) / path
    return str(path.resolve())


def resolve_scenario(scenario: Scenario) -> dict[str, Any]:
    """The scenario as fully resolved plain data (see the module docstring); loading it gives the same run.

    Args:
        scenario: A validated scenario.

    Returns:
        A JSON-compatible dict.

    Raises:
        MapError: The map is neither a built-in map's name nor a file path (field ``map``).
    """
    data = scenario.to_dict()
    data["algorithm"]["params"] = scenario.algorithm_params().model_dump(mode="json")
    data["map"] = _resolved_map(scenario)
    # a trajectory file's path is absolute already (Scenario.to_dict); without one the field is left out, so the
    # runs of the stores written before it existed keep their hashes
    if data["agents"].get("trajectories") is None:
        del data["agents"]["trajectories"]
    return data


def _stamp(path: Path) -> tuple[str, int, int] | None:
    """``(path, mtime_ns, size)`` of a regular file (the cache key of its digest), ``None`` when there is none."""
    try:
        st = path.stat()
    except (OSError, ValueError):
        return None
    return (str(path), st.st_mtime_ns, st.st_size) if stat.S_ISREG(st.st_mode) else None


@functools.lru_cache(maxsize=512)
def _file_sha(path: str, mtime_ns: int, size: int) -> str:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return _MISSING


@functools.lru_cache(maxsize=512)
def _yaml_sha_and_image(path: str, mtime_ns: int, size: int) -> tuple[str, str | None]:
    """SHA-256 of a map YAML file's bytes and the image it names (``None`` when it names none)."""
    try:
        raw = Path(path).read_bytes()
    except OSError:
        return _MISSING, None
    try:  # read as the map loader reads it (too deep, a key twice: no image; loading the map says why)
        data = load_yaml(raw, "map")
    except ScenarioError:
        data = None
    image = data.get("image") if isinstance(data, dict) else None
    return hashlib.sha256(raw).hexdigest(), image if isinstance(image, str) and image.strip() else None


def _digest_of_yaml(yaml_path: Path) -> str:
    stamp = _stamp(yaml_path)
    if stamp is None:
        return _MISSING
    yaml_sha, image = _yaml_sha_and_image(*stamp)
    image_sha = _MISSING
    if image is not None:
        image_path = Path(image) if Path(image).is_absolute() else yaml_path.parent / image
        image_stamp = _stamp(image_path)
        image_sha = _file_sha(*image_stamp) if image_stamp is not None else _MISSING
    return hashlib.sha256(f"{yaml_sha}:{image_sha}".encode()).hexdigest()


def map_digest(ref: str) -> str:
    """SHA-256 (hex) of a map's content: its YAML file's bytes and the bytes of the image the YAML names.

    Args:
        ref: A resolved scenario's ``map``: a built-in map's name (its files in ``amronet/data/maps`` are
            hashed) or the absolute path of a map YAML file.

    Returns:
        The digest; a missing file (YAML or image) hashes as ``"missing"``, so creating it later changes the
        digest. Cached per file path, modification time and size: cheap to call for every point of a sweep.
    """
    if ref in BUILTIN_MAPS:
        with resources.as_file(resources.files("amronet").joinpath("data", "maps")) as folder:
            return _digest_of_yaml(Path(folder) / f"{ref}.yaml")
    return _digest_of_yaml(Path(ref))


def scenario_hash(resolved: dict[str, Any]) -> str:
    """SHA-256 (hex) of a resolved scenario's canonical JSON and of its map's content (:func:`map_digest`).

    A scenario with an agents' trajectory file (``agents.trajectories``) hashes the file's bytes too, so editing
    it makes new runs.
    """
    h = hashlib.sha256(canonical_json(resolved).encode())
    h.update(b"\nmap-content:" + map_digest(str(resolved.get("map", ""))).encode())
    paths = (resolved.get("agents") or {}).get("trajectories")
    if paths:  # only scenarios with a trajectory file: every other hash stays what it was
        stamp = _stamp(Path(paths))
        h.update(b"\ntrajectories-content:" + (_file_sha(*stamp) if stamp is not None else _MISSING).encode())
    return h.hexdigest()
