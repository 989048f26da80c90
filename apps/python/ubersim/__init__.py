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
import os as _os

from ._ubersim import ModelError, PluginError, SnapshotError  # noqa: F401
from ._ubersim import World as _World

__all__ = ["World", "ModelError", "PluginError", "SnapshotError"]

# In the build tree the plugins are at <build>/lib/ubersim/plugins, beside <build>/python/ubersim.
_BUILD_PLUGINS = _os.path.normpath(_os.path.join(_os.path.dirname(__file__), "..", "..", "lib", "ubersim", "plugins"))


class World(_World):
    """One simulated SSL field: loaded as `ubersim run` loads it (its plugins too), no transports."""

    def __init__(self, world, plugin_paths=(), seed=None, profile=None):
        paths = list(plugin_paths)
        if _os.path.isdir(_BUILD_PLUGINS):
            paths.append(_BUILD_PLUGINS)
        super().__init__(str(world), paths, seed, profile)
