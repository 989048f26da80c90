# SPDX-License-Identifier: Apache-2.0
"""ÜberSim for Python: a RoboCup SSL world of the kernel's public API, without sockets.

    import ubersim
    world = ubersim.World("div-b", seed=7)          # a shipped world's name, or a world file
    world.command("blue", 0, vx=1.0)                # 1 m/s forward, the robot's frame
    world.step(200)                                 # 200 physics steps
    state = world.state()                           # numpy arrays, SI units, the field frame

Errors carry the command line's text and exit code: ModelError (3, file:line:column: key),
PluginError (4), SnapshotError (1). docs/python.md.
"""
from ._paths import plugin_paths as _plugin_paths
from ._ubersim import ModelError, PluginError, SnapshotError  # noqa: F401
from ._ubersim import World as _World


class World(_World):
    """One simulated SSL field: loaded as `ubersim run` loads it (its plugins too), no transports."""

    def __init__(self, world, plugin_paths=(), seed=None, profile=None, physics=None, robot=None):
        super().__init__(str(world), _plugin_paths(plugin_paths), seed, profile, physics,
                         None if robot is None else str(robot))


from . import tasks  # noqa: E402
from .env import Env, ParallelEnv, VectorEnv  # noqa: E402
from .render import render_field  # noqa: E402

__all__ = ["World", "VectorEnv", "Env", "ParallelEnv", "tasks", "render_field", "ModelError", "PluginError",
           "SnapshotError"]
