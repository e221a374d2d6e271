"""Robot models by name: footprint, speed and range sensors (light: the scenario checks names without the engine)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["AMIGOBOT", "BEBOT", "PIONEER", "ROBOT_MODELS", "RobotModel"]


@dataclass(frozen=True)
class RobotModel:
    """Physical model of a robot: a disc with a ring of range sensors.

    Attributes:
        name: Model name.
        radius: Footprint radius in metres.
        max_speed: Maximum speed in metres per second (0 for immobile robots).
        sensor_beams: Number of equally spaced range sensors around the body (beam 0 points forward).
        sensor_range: Maximum range of each sensor in metres.
    """

    name: str
    radius: float
    max_speed: float
    sensor_beams: int
    sensor_range: float


PIONEER = RobotModel("pioneer", radius=0.22, max_speed=0.5, sensor_beams=16, sensor_range=2.0)
"""Agent, after the Pioneer 2-DX of the paper's experiments: 16 sonars with 2 m range."""
BEBOT = RobotModel("bebot", radius=0.045, max_speed=0.2, sensor_beams=12, sensor_range=0.14)
"""Router, after the Bebot mini-robot: 12 infrared sensors with 0.14 m range."""
AMIGOBOT = RobotModel("amigobot", radius=0.165, max_speed=0.0, sensor_beams=8, sensor_range=1.0)
"""Base-station reference node, after the AmigoBot; immobile."""

ROBOT_MODELS: dict[str, RobotModel] = {k.name: k for k in (PIONEER, BEBOT, AMIGOBOT)}
"""The built-in robot models by name (``bebot``, ``pioneer``, ``amigobot``)."""
