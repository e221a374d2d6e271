"""The ``"random"`` explorer: the paper's random exploration with sonar-based obstacle avoidance."""

from __future__ import annotations

import numpy as np

from amronet.algorithms.explorers.base import EXPLORERS, Explorer
from amronet.engine.motion import random_walk

__all__ = ["RandomExplorer"]


@EXPLORERS.register("random")
class RandomExplorer(Explorer):
    """Random exploration with sonar-based obstacle avoidance (the paper's agents).

    Agents keep their heading up to Gaussian noise; when a forward sonar reads less than ``avoid_range`` they
    turn away from what they see; after a refused move they pick a uniform random heading.
    """

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        reach = min(sensor_range, self.avoid_range)
        random_walk(heading, who, np.minimum(scans, reach), reach, refused, rng, self.turn_noise * np.sqrt(self.dt))
