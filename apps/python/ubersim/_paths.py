# SPDX-License-Identifier: Apache-2.0
"""Where the package finds its plugins and data: inside it when installed by pip (setup.py lays it
out as an install prefix: lib/ubersim/plugins, share/ubersim), else in the build tree."""
import os

_HERE = os.path.dirname(os.path.abspath(__file__))
_INSTALLED_PLUGINS = os.path.join(_HERE, "lib", "ubersim", "plugins")
_INSTALLED_DATA = os.path.join(_HERE, "share", "ubersim")
# In the build tree: <build>/lib/ubersim/plugins, beside <build>/python/ubersim.
_BUILD_PLUGINS = os.path.normpath(os.path.join(_HERE, "..", "..", "lib", "ubersim", "plugins"))

# The kernel finds models/ and schemas/ through UBERSIM_DATA_DIR (kernel/data_paths.hpp); next to
# the running executable would be /usr/bin for Python. A user's own setting stays.
if os.path.isdir(os.path.join(_INSTALLED_DATA, "models")):
    os.environ.setdefault("UBERSIM_DATA_DIR", _INSTALLED_DATA)


def plugin_paths(extra=()):
    """The caller's plugin folders, then the package's own."""
    paths = [str(p) for p in extra]
    paths.extend(p for p in (_INSTALLED_PLUGINS, _BUILD_PLUGINS) if os.path.isdir(p))
    return paths
