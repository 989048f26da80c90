# SPDX-License-Identifier: Apache-2.0
"""Type stubs of `ubersim` (docs/python.md), so that editors complete it."""
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union
import os

import numpy as np
import numpy.typing as npt

from . import tasks as tasks
from .render import render_field as render_field

__all__ = ["World", "VectorEnv", "Env", "ParallelEnv", "tasks", "render_field", "ModelError", "PluginError",
           "SnapshotError"]

Array = npt.NDArray[np.float32]
Physics = Optional[Mapping[str, Union[int, float, str]]]
# A task: an object with evaluate(obs, actions, env) -> (reward, terminated) and optionally start
# and begin (ubersim.tasks.Task), or a callable with evaluate's signature.
TaskLike = Any

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
                 profile: Optional[str] = ..., physics: Physics = ..., robot: Optional[Union[str, os.PathLike]] = ...
                 ) -> None:
        """Loads WORLD (a file, or a shipped world's name such as 'div-b'); seed and profile override the file's,
        physics sets physics keys over the profile (step s, solver_iterations, max_contacts, erp, cfm, …), robot a
        robot model file for every robot."""
    def random_play(self, seed: Optional[int]) -> None:
        """The bench's seeded random play drives every robot from now on (None stops it)."""
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
    def reset(self, seed: Optional[int] = None) -> None:
        """Puts everything back where the world file has it (with another seed when given)."""
    @property
    def field(self) -> Dict[str, Any]:
        """The field's geometry: sizes (m), lines (x1, y1, x2, y2, thickness) and arcs (cx, cy, r, a1, a2, thickness)."""
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

class VectorWorlds:
    """The C++ core of the environments: K worlds stepped by one call."""
    def state_hash(self, index: int) -> int:
        """World `index`'s state hash."""
    def time(self, index: int) -> float:
        """World `index`'s simulated time, s."""
    def save(self, index: int) -> bytes:
        """World `index`'s full state."""
    def restore(self, index: int, snapshot: bytes) -> None:
        """Puts a saved state back into world `index`."""
    profile: str  # the physics profile in force
    physics_steps: int  # physics steps of all worlds so far
    step_seconds: float  # the physics step, s

class Box:
    """gymnasium.spaces.Box when gymnasium is importable, else one of the same behaviour."""
    shape: Tuple[int, ...]
    dtype: np.dtype
    low: npt.NDArray[Any]
    high: npt.NDArray[Any]
    def sample(self) -> npt.NDArray[Any]: ...
    def contains(self, x: Any) -> bool: ...
    def seed(self, seed: Optional[int] = None) -> List[Optional[int]]: ...

class VectorEnv:
    """K worlds of one world file stepped by one call into C++, in gymnasium's VectorEnv API.
    Observations K × robots × features (ubersim.env.FEATURES), actions K × controlled × 6 (ubersim.env.ACTION)."""
    num_envs: int
    single_observation_space: Box
    single_action_space: Box
    observation_space: Box
    action_space: Box
    render_mode: Optional[str]
    metadata: Dict[str, Any]
    def __init__(self, world: Union[str, os.PathLike] = "div-b", num_envs: int = 1, *, task: TaskLike = None,
                 controlled: str = "blue", opponent: str = "idle", frame_skip: int = 5,
                 max_episode_steps: Optional[int] = None, camera_features: bool = False,
                 render_mode: Optional[str] = None, seed: Optional[int] = None, profile: Optional[str] = "fast",
                 physics: Physics = None, robot: Optional[str] = None, plugin_paths: Iterable[str] = (),
                 copy: bool = True) -> None:
        """controlled: 'blue', 'yellow', 'both' or 'none'; opponent: 'idle', 'scripted' or 'random';
        copy=False: observations are the env's own buffer, overwritten by the next step."""
    def reset(self, *, seed: Optional[Union[int, Sequence[int]]] = None,
              options: Optional[Dict[str, Any]] = None) -> Tuple[Array, Dict[str, Any]]:
        """Starts a new episode in every world; world k gets seed + k (or its own of a list)."""
    def step(self, actions: npt.ArrayLike) -> Tuple[Array, npt.NDArray[np.float64], npt.NDArray[np.bool_],
                                                    npt.NDArray[np.bool_], Dict[str, Any]]:
        """(obs, reward, terminated, truncated, info) over the K worlds; done worlds reset at once
        (their final observation in info['final_obs'], mask info['_final_obs'])."""
    def render(self) -> Optional[Tuple[npt.NDArray[np.uint8], ...]]:
        """Each world's field as an RGB array (H × W × 3), or None without render_mode='rgb_array'."""
    def close(self) -> None:
        """Frees the worlds."""
    @property
    def worlds(self) -> VectorWorlds:
        """The C++ core: state_hash(k), save(k), restore(k, bytes), time(k), profile."""
    @property
    def features(self) -> Tuple[str, ...]:
        """The observation's feature names, in order."""
    @property
    def slots(self) -> npt.NDArray[np.int32]:
        """Each robot row's (team, id): team 0 blue, 1 yellow."""
    @property
    def controlled_rows(self) -> npt.NDArray[np.int32]:
        """The robot rows the actions move, in the actions' order."""
    @property
    def field(self) -> Dict[str, Any]:
        """The field's geometry (m)."""
    @property
    def dt(self) -> float:
        """Simulated seconds per env step."""
    @property
    def unwrapped(self) -> "VectorEnv":
        """This env (gymnasium's wrappers' contract)."""

class Env:
    """One world in gymnasium's Env API (the options of VectorEnv, no auto-reset)."""
    observation_space: Box
    action_space: Box
    render_mode: Optional[str]
    metadata: Dict[str, Any]
    def __init__(self, world: Union[str, os.PathLike] = "div-b", *, task: TaskLike = None, controlled: str = "blue",
                 opponent: str = "idle", frame_skip: int = 5, max_episode_steps: Optional[int] = None,
                 camera_features: bool = False, render_mode: Optional[str] = None, seed: Optional[int] = None,
                 profile: Optional[str] = "fast", physics: Physics = None, robot: Optional[str] = None,
                 plugin_paths: Iterable[str] = ()) -> None: ...
    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
              ) -> Tuple[Array, Dict[str, Any]]:
        """Starts a new episode: (obs robots × features, info)."""
    def step(self, action: npt.ArrayLike) -> Tuple[Array, float, bool, bool, Dict[str, Any]]:
        """(obs, reward, terminated, truncated, info)."""
    def render(self) -> Optional[npt.NDArray[np.uint8]]:
        """The field as an RGB array, or None without render_mode."""
    def close(self) -> None:
        """Frees the world."""
    @property
    def world(self) -> VectorWorlds:
        """The C++ core of the one world (index 0)."""
    @property
    def worlds(self) -> VectorWorlds:
        """The same C++ core (the name VectorEnv and ParallelEnv use)."""
    @property
    def features(self) -> Tuple[str, ...]: ...
    @property
    def slots(self) -> npt.NDArray[np.int32]: ...
    @property
    def controlled_rows(self) -> npt.NDArray[np.int32]: ...
    @property
    def field(self) -> Dict[str, Any]: ...
    @property
    def dt(self) -> float: ...
    @property
    def unwrapped(self) -> "Env": ...

class ParallelEnv:
    """Every robot an agent ('blue_0' … 'yellow_10') over K worlds, PettingZoo's parallel API batched:
    each dict value has the K worlds as its first axis."""
    possible_agents: List[str]
    agents: List[str]
    agent_row: Dict[str, int]
    num_envs: int
    render_mode: Optional[str]
    metadata: Dict[str, Any]
    def __init__(self, world: Union[str, os.PathLike] = "div-b", num_envs: int = 1, *, task: TaskLike = None,
                 blue: str = "agent", yellow: str = "agent", frame_skip: int = 5,
                 max_episode_steps: Optional[int] = None, camera_features: bool = False,
                 render_mode: Optional[str] = None, seed: Optional[int] = None, profile: Optional[str] = "fast",
                 physics: Physics = None, robot: Optional[str] = None, plugin_paths: Iterable[str] = ()) -> None: ...
    def reset(self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
              ) -> Tuple[Dict[str, Array], Dict[str, Dict[str, Any]]]:
        """(observations, infos): each agent's K × robots × features view."""
    def step(self, actions: Mapping[str, npt.ArrayLike]) -> Tuple[Dict[str, Array], Dict[str, npt.NDArray[np.float64]],
                                                                  Dict[str, npt.NDArray[np.bool_]],
                                                                  Dict[str, npt.NDArray[np.bool_]], Dict[str, Any]]:
        """actions: agent → K × 6. (observations, rewards, terminations, truncations, infos)."""
    def step_array(self, actions: npt.ArrayLike) -> Tuple[Dict[str, Array], Dict[str, npt.NDArray[np.float64]],
                                                          Dict[str, npt.NDArray[np.bool_]],
                                                          Dict[str, npt.NDArray[np.bool_]], Dict[str, Any]]:
        """The same with every agent's actions in one K × agents × 6 array."""
    def observation_space(self, agent: str) -> Box:
        """One world's observation of `agent`."""
    def action_space(self, agent: str) -> Box:
        """One world's action of `agent`."""
    def render(self) -> Optional[Tuple[npt.NDArray[np.uint8], ...]]: ...
    def close(self) -> None: ...
    @property
    def num_agents(self) -> int: ...
    @property
    def max_num_agents(self) -> int: ...
    @property
    def worlds(self) -> VectorWorlds: ...
    @property
    def features(self) -> Tuple[str, ...]: ...
    @property
    def slots(self) -> npt.NDArray[np.int32]:
        """Each robot row's (team, id) in the field's order (the views reorder them)."""
    @property
    def controlled_rows(self) -> npt.NDArray[np.int32]:
        """The robot rows of the agents, in possible_agents' order."""
    @property
    def field(self) -> Dict[str, Any]: ...
    @property
    def dt(self) -> float: ...
