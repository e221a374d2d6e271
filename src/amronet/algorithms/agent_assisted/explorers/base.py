"""What an explorer is, and the registry scenarios pick one from by name (``algorithm.params.explorer``)."""

from __future__ import annotations

import numpy as np

from amronet.registry import Registry

__all__ = ["EXPLORERS", "Explorer"]


class Explorer:
    """Base class: decide agents' headings.

    Explorers may use only what agents can know: their own sonar readings, positions and headings, and what the
    AMRoNet tells them (positions of the deployed routers). ``extent`` and ``resolution`` describe the area's
    bounding box for bookkeeping grids; explorers must not read the map's cells.

    Args:
        turn_noise: Heading noise in radians per square-root second.
        avoid_range: Readings nearer than this trigger obstacle avoidance (metres).
        dt: Step length.
        r_c: Communication radius.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
    """

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float]) -> None:
        self.turn_noise = turn_noise
        self.avoid_range = avoid_range
        self.dt = dt
        self.r_c = r_c
        self.extent = extent

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        """Update ``heading[who]`` in place.

        Args:
            heading: Headings of all robots (entries ``who`` are updated).
            who: The agents.
            scans: Their sonar ranges ``(A, n_beams)``, beam 0 along the heading, beams evenly spaced.
            sensor_range: Maximum sonar range.
            refused: Which agents had their last move refused ``(A,)``.
            rng: The run's random generator.
            xy: Positions of all robots.
            deployed_xy: Positions of the base nodes and deployed routers (what the AMRoNet reports).
        """
        raise NotImplementedError

    def speed(self, max_speed: np.ndarray) -> np.ndarray:
        """Speeds of the agents steered last, in the order given to :meth:`steer` (default: their top speeds).

        Args:
            max_speed: The agents' top speeds ``(A,)``.
        """
        return max_speed.copy()

    def active(self, m: int) -> np.ndarray:
        """Which of the ``m`` agents given to :meth:`steer` keep the run going (default: all; exploring never ends)."""
        return np.ones(m, dtype=bool)

    def report(self) -> dict[str, object]:
        """Numbers for the summary's ``mission`` section (default: none)."""
        return {}


EXPLORERS: Registry[type[Explorer]] = Registry("explorer")
"""Exploration strategies by name; register one with ``@EXPLORERS.register("name")``."""
