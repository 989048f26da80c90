# SPDX-License-Identifier: Apache-2.0
"""pip's route to `import ubersim` (docs/python.md), offline, with Debian's /usr/bin/python3:

    /usr/bin/python3 -m venv --system-site-packages venv
    venv/bin/pip install --no-build-isolation --no-index .

The build step is CMake's. It builds the package's targets in a CMake build tree, installs the
project into a staging prefix (its install() rules, stripped), and lays the wheel's `ubersim`
package out as an install prefix of its own, so that nothing points back at the checkout or the
build tree once it is installed:

    ubersim/__init__.py, *.py, *.pyi, py.typed  apps/python/ubersim
    ubersim/_ubersim.<abi>.so                   the module, its RUNPATH set to $ORIGIN/lib
    ubersim/lib/libubersim_*.so.<version>       the project's shared libraries the module and the plugins need
    ubersim/lib/ubersim/plugins/*.so            the plugins (their install RUNPATH is $ORIGIN/../..)
    ubersim/share/ubersim/{models,schemas}      the shipped models and their schemas
    <pkg>_pb2.py (top level)                    only the generated protocol messages the package imports

Environment:
    UBERSIM_BUILD_DIR=<dir>    the CMake build tree. A configured tree (a developer's build/) is reused:
                               only its out-of-date parts are rebuilt. An empty folder is configured.
                               Default: build-pip/ in the checkout (Release, without tests).
    UBERSIM_NO_BUILD=1         package the build tree as it is, building nothing.
    CMAKE_BUILD_PARALLEL_LEVEL the number of build jobs (CMake's own variable).

setuptools' own scratch space (its build/ folder and the *.egg-info) goes to a temporary folder that
is removed at exit: build/ in the checkout is the CMake tree, and the checkout stays as it was.
"""
import atexit
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from setuptools import Extension, find_packages, setup
from setuptools.command.build_ext import build_ext

SOURCE_DIR = Path(__file__).resolve().parent
PYTHON_DIR = "apps/python"  # the package's sources; setuptools wants it relative to setup.py
# Where the project's CMakeLists put their outputs, relative to the build tree.
MODULE_OUTPUT_DIR = Path("python/ubersim")  # apps/python/CMakeLists.txt
PROTO_OUTPUT_DIR = Path("python")  # plugins/transports/proto/CMakeLists.txt
PLUGIN_OUTPUT_DIR = "lib/ubersim/plugins"  # CMakeLists.txt: UBERSIM_PLUGIN_OUTPUT_DIR
PROTO_NAME = re.compile(r"\b([A-Za-z_][A-Za-z0-9_]*_pb2)\b")  # a generated message module's name
# What the package needs built besides the plugins; `ubersim` (the command line) only because the
# project's install rules install it.
PACKAGE_TARGETS = ["_ubersim", "ubersim_python", "ubersim_ssl_proto_python", "ubersim"]

SCRATCH = Path(tempfile.mkdtemp(prefix="ubersim-setup-"))
atexit.register(shutil.rmtree, SCRATCH, True)


def project_version():
    text = (SOURCE_DIR / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(\s*ubersim\s+VERSION\s+([0-9][0-9.]*)", text)
    if not match:
        raise RuntimeError("cannot read the version from project(ubersim VERSION ...) in CMakeLists.txt")
    return match.group(1)


def run(command, **kwargs):
    command = [str(c) for c in command]
    print("+ " + " ".join(command), flush=True)
    return subprocess.run(command, check=True, **kwargs)


def read_cache(build_dir):
    values = {}
    for line in (build_dir / "CMakeCache.txt").read_text(encoding="utf-8", errors="replace").splitlines():
        match = re.match(r"([A-Za-z0-9_.\-]+):[A-Z]+=(.*)$", line)
        if match:
            values[match.group(1)] = match.group(2)
    return values


def build_targets(build_dir, cache):
    """The package's targets and every plugin's library (found in Ninja's target list); `all` with
    another generator."""
    if cache.get("CMAKE_GENERATOR") != "Ninja":
        return ["all"]
    ninja = cache.get("CMAKE_MAKE_PROGRAM") or "ninja"
    listing = run([ninja, "-C", build_dir, "-t", "targets", "all"], capture_output=True, text=True).stdout
    plugins = sorted({line.split(":", 1)[0] for line in listing.splitlines()
                      if line.startswith(PLUGIN_OUTPUT_DIR + "/") and line.split(":", 1)[0].endswith(".so")})
    return PACKAGE_TARGETS + plugins


def cmake_build_tree():
    """The configured, built CMake tree and its cache (see the module's docstring)."""
    chosen = os.environ.get("UBERSIM_BUILD_DIR")
    build_dir = Path(chosen).expanduser().resolve() if chosen else SOURCE_DIR / "build-pip"
    no_build = os.environ.get("UBERSIM_NO_BUILD", "") not in ("", "0")
    if not (build_dir / "CMakeCache.txt").is_file():
        if no_build:
            raise RuntimeError(f"UBERSIM_NO_BUILD is set, but {build_dir} is not a configured CMake build tree")
        run(["cmake", "-S", SOURCE_DIR, "-B", build_dir, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
             "-DUBERSIM_BUILD_TESTS=OFF", "-DUBERSIM_BUILD_BENCHMARKS=OFF"])
    cache = read_cache(build_dir)
    home = cache.get("CMAKE_HOME_DIRECTORY")
    if home and Path(home).resolve() != SOURCE_DIR:
        raise RuntimeError(f"{build_dir} was configured from {home}, not from this checkout ({SOURCE_DIR})")
    if cache.get("UBERSIM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES"):
        raise RuntimeError(f"{build_dir} is a sanitizer build: Python cannot load its module")
    if not no_build:
        run(["cmake", "--build", build_dir, "--target", *build_targets(build_dir, cache)])
    return build_dir, cache


def needed_libraries(readelf, binary):
    """The DT_NEEDED names of an ELF file."""
    dynamic = run([readelf, "-d", binary], capture_output=True, text=True).stdout
    return re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic)


def set_runpath(binary, runpath):
    """Rewrites BINARY's RUNPATH in place with CMake (it fails if RUNPATH is longer than the old one)."""
    script = SCRATCH / "set_runpath.cmake"
    script.write_text('file(RPATH_SET FILE "${BINARY}" NEW_RPATH "${RUNPATH}")\n', encoding="utf-8")
    run(["cmake", f"-DBINARY={binary}", f"-DRUNPATH={runpath}", "-P", script])


def imported_protos(package_dir, proto_dir):
    """The generated *_pb2 modules the package imports, with the ones they import in turn."""
    pending = list(package_dir.rglob("*.py"))
    found = set()
    while pending:
        text = pending.pop().read_text(encoding="utf-8", errors="replace")
        for name in PROTO_NAME.findall(text):
            candidate = proto_dir / f"{name}.py"
            if name not in found and candidate.is_file():
                found.add(name)
                pending.append(candidate)
    return sorted(found)


def uses_protos():
    """Whether the package imports generated protocol messages (then it needs Debian's python3-protobuf)."""
    return any(PROTO_NAME.search(p.read_text(encoding="utf-8", errors="replace"))
               for p in (SOURCE_DIR / PYTHON_DIR / "ubersim").rglob("*.py"))


class BuildWithCMake(build_ext):
    """build_ext: the module, the libraries, the plugins and the data, from the CMake build."""

    def run(self):
        if self.inplace:
            raise RuntimeError("editable installs are not supported; in a checkout, use "
                               "PYTHONPATH=build/python /usr/bin/python3 (docs/python.md)")
        build_dir, cache = cmake_build_tree()
        prefix = SCRATCH / "prefix"
        run(["cmake", "--install", build_dir, "--prefix", prefix, "--strip"], stdout=subprocess.DEVNULL)
        libdir = prefix / (cache.get("CMAKE_INSTALL_LIBDIR") or "lib")
        datadir = prefix / (cache.get("CMAKE_INSTALL_DATADIR") or cache.get("CMAKE_INSTALL_DATAROOTDIR") or "share")
        readelf = cache.get("CMAKE_READELF") or "readelf"
        strip = cache.get("CMAKE_STRIP") or "strip"

        module = Path(self.get_ext_fullpath("ubersim._ubersim"))
        package = module.parent
        built_module = build_dir / MODULE_OUTPUT_DIR / module.name
        if not built_module.is_file():
            present = sorted(p.name for p in (build_dir / MODULE_OUTPUT_DIR).glob("_ubersim*"))
            raise RuntimeError(f"{built_module} is missing (found {present or 'nothing'}): the module is built "
                               "for Debian's /usr/bin/python3; run pip with that interpreter")
        package.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built_module, module)
        run([strip, module])
        set_runpath(module, "$ORIGIN/lib")

        plugins = package / "lib" / "ubersim" / "plugins"
        shutil.copytree(libdir / "ubersim" / "plugins", plugins, dirs_exist_ok=True)

        # The project's own libraries that the module and the plugins load (their SONAMEs), no more.
        pending = [module, *sorted(plugins.glob("*.so"))]
        copied = set()
        while pending:
            for name in needed_libraries(readelf, pending.pop()):
                source = libdir / name
                if name not in copied and source.exists():
                    copied.add(name)
                    shutil.copyfile(source, package / "lib" / name)  # follows the SONAME's symlink
                    pending.append(package / "lib" / name)

        for folder in ("models", "schemas"):
            shutil.copytree(datadir / "ubersim" / folder, package / "share" / "ubersim" / folder, dirs_exist_ok=True)

        for name in imported_protos(SOURCE_DIR / PYTHON_DIR / "ubersim", build_dir / PROTO_OUTPUT_DIR):
            shutil.copyfile(build_dir / PROTO_OUTPUT_DIR / f"{name}.py", Path(self.build_lib) / f"{name}.py")


setup(
    name="ubersim",
    version=project_version(),
    description="ÜberSim, a RoboCup SSL simulator: its kernel in Python (worlds, steps, numpy state)",
    license="Apache-2.0",
    python_requires=">=3.9",
    packages=find_packages(PYTHON_DIR, include=["ubersim", "ubersim.*"]),
    package_dir={"": PYTHON_DIR},
    package_data={"": ["*.pyi", "py.typed"]},
    ext_modules=[Extension("ubersim._ubersim", sources=[])],
    cmdclass={"build_ext": BuildWithCMake},
    install_requires=["numpy", *(["protobuf"] if uses_protos() else [])],
    zip_safe=False,
    options={"build": {"build_base": str(SCRATCH / "build")}, "egg_info": {"egg_base": str(SCRATCH)}},
)
