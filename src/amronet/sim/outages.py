"""The agents' connection, step by step: how long each was connected, its outages and the longest."""

from __future__ import annotations

import numpy as np

__all__ = ["OutageTracker"]


class OutageTracker:
    """Per agent, step by step: steps connected to a base station, outages and the longest outage.

    An *outage* is a maximal stretch of consecutive observed steps in which an agent has no path to a base
    station. It is counted when it begins and its length grows while it lasts, so an outage still going on when
    the run ends counts, closed at the end. Every update is a handful of array operations over the agents.

    The initial state (before the first step) is what the tracker is made with; like
    :attr:`Run.agents_connected_fraction`, it counts only while no step has been observed: then it stands as the
    one observation (an agent cut off in it has one outage, of 0 steps: no time has passed).

    Args:
        initial: Which agents are connected in the initial state, boolean ``(A,)``.
    """

    def __init__(self, initial: np.ndarray) -> None:
        self.initial = np.array(initial, dtype=bool)
        n = len(self.initial)
        self.steps = 0
        """Steps observed."""
        self.all_connected_steps = 0
        """Steps in which every agent was connected."""
        self.connected_steps = np.zeros(n, dtype=np.int64)
        self._outages = np.zeros(n, dtype=np.int64)
        self._longest = np.zeros(n, dtype=np.int64)
        self._current = np.zeros(n, dtype=np.int64)
        """Length in steps of each agent's outage going on now (0: connected at the last step)."""
        self._any_current = False

    def observe(self, linked: np.ndarray) -> None:
        """Account for one step: ``linked`` says which agents are connected after it, boolean ``(A,)``."""
        self.steps += 1
        if np.count_nonzero(linked) == len(linked):  # linked.all(), at a tenth of its cost on a few agents
            self.all_connected_steps += 1
            self.connected_steps += 1
            if self._any_current:
                self._current[:] = 0
                self._any_current = False
            return
        down = ~linked
        self.connected_steps += linked
        self._outages += down & (self._current == 0)
        self._current += down
        self._current[linked] = 0
        np.maximum(self._longest, self._current, out=self._longest)
        self._any_current = True

    def live_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The per-agent arrays themselves, for a compiled caller to keep them in place.

        Returns:
            ``(connected_steps, outages, longest, current)``: steps connected, outages begun, the longest outage and
            the one going on now (0: connected at the last step), in steps.
        """
        return self.connected_steps, self._outages, self._longest, self._current

    def counts(self) -> tuple[int, int, bool]:
        """The tracker's numbers beside its arrays; hand them back to :meth:`set_counts` after observing elsewhere.

        Returns:
            ``(steps, all_connected_steps, ongoing)``: steps observed, steps with every agent connected, and whether
            some agent's outage is going on now.
        """
        return self.steps, self.all_connected_steps, self._any_current

    def set_counts(self, steps: int, all_connected_steps: int, ongoing: bool) -> None:
        """Take back the numbers of :meth:`counts` after steps observed by a compiled caller in the live arrays."""
        self.steps, self.all_connected_steps, self._any_current = int(steps), int(all_connected_steps), bool(ongoing)

    @property
    def connected_fraction(self) -> np.ndarray:
        """Per agent, the fraction of steps connected (without steps: 1 or 0 by the initial state)."""
        if self.steps == 0:
            return self.initial.astype(float)
        return self.connected_steps / self.steps

    @property
    def outages(self) -> np.ndarray:
        """Per agent, the number of outages (without steps: 1 for an agent cut off in the initial state)."""
        if self.steps == 0:
            return (~self.initial).astype(np.int64)
        return self._outages.copy()

    @property
    def longest_outage_steps(self) -> np.ndarray:
        """Per agent, the length in steps of its longest outage (0 without one)."""
        return self._longest.copy()

    @property
    def all_connected_fraction(self) -> float:
        """Fraction of steps in which every agent was connected (without steps: by the initial state)."""
        if self.steps == 0:
            return float(self.initial.all())
        return self.all_connected_steps / self.steps
