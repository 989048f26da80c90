# SPDX-License-Identifier: Apache-2.0
"""Type stubs of `ubersim` (docs/python.md), so that editors complete it."""
from typing import Dict, Iterable, Optional, Union
import os

import numpy as np
import numpy.typing as npt

__all__ = ["World", "ModelError", "PluginError", "SnapshotError"]

class ModelError(ValueError):
    """A model file that cannot be read or is invalid: file:line:column: key: reason."""
    exit_code: int  # 3, as `ubersim` exits

class PluginError(RuntimeError):
    """A plugin that is missing, refused or failing: its path and why."""
    exit_code: int  # 4

class SnapshotError(ValueError):
    """Bytes given to restore that are not a snapshot of this world."""
    exit_code: int  # 1

class World:
    """One simulated SSL field, loaded as `ubersim run` loads it (its plugins too), without sockets."""

    def __init__(self, world: Union[str, os.PathLike], plugin_paths: Iterable[str] = ..., seed: Optional[int] = ...,
                 profile: Optional[str] = ...) -> None:
        """Loads WORLD (a file, or a shipped world's name such as 'div-b'); seed and profile override the file's."""
    def step(self, steps: int = 1) -> None:
        """Advances the world by `steps` physics steps."""
    def state(self) -> Dict[str, Union[float, npt.NDArray[np.float64], npt.NDArray[np.int32], npt.NDArray[np.bool_]]]:
        """time (s); robot_ids (N×2: team 0 blue / 1 yellow, id); robot_pose (N×3: x, y, yaw);
        robot_velocity (N×3: vx, vy, ω); robot_present (N); ball_position (3); ball_velocity (3). SI, field frame."""
    def command(self, team: str, id: int, vx: float = 0.0, vy: float = 0.0, angular: float = 0.0,
                global_frame: bool = False, kick_speed: float = 0.0, chip_angle: float = 0.0,
                dribbler: Optional[float] = None) -> None:
        """A robot command: m/s in the robot's frame (or the field's), rad/s; a kick (m/s, rad); dribbler (rad/s)."""
    def place_ball(self, x: float, y: float, z: float = 0.0215, vx: float = 0.0, vy: float = 0.0,
                   vz: float = 0.0) -> None:
        """Puts the ball at (x, y, z) m with velocity (vx, vy, vz) m/s."""
    def place_robot(self, team: str, id: int, x: float, y: float, yaw: float = 0.0, present: bool = True) -> None:
        """Puts a robot at (x, y) m heading yaw rad, or takes it off the field."""
    def save(self) -> bytes:
        """The world's full state (a snapshot)."""
    def restore(self, snapshot: bytes) -> None:
        """Puts a saved state back: stepping on is bit-identical."""
    def reset(self) -> None:
        """Puts everything back where the world file has it."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def steps(self) -> int:
        """Physics steps since the start."""
    @property
    def step_seconds(self) -> float:
        """The physics step, s."""
    @property
    def state_hash(self) -> int:
        """A hash of every body's state, bit for bit."""
    @property
    def name(self) -> str:
        """The world's name."""
    @property
    def log(self) -> str:
        """What the world logged (warnings and errors)."""
