# SPDX-License-Identifier: Apache-2.0
"""`pip install --no-build-isolation --no-index` from the checkout into a fresh venv (setup.py).

The install reuses the build tree as it is (UBERSIM_BUILD_DIR, UBERSIM_NO_BUILD=1: nothing is
rebuilt) and downloads nothing. The installed package is then imported in a clean environment (no
PYTHONPATH, a temporary working folder) and must step 'div-b' to the same state hash as the build
tree's module, with every ÜberSim library it maps coming from the venv. Where a private mount
namespace is allowed (`unshare -rm`), the checkout and the build tree are hidden meanwhile, so the
kernel's compiled-in fallback to the source tree's models/ cannot stand in for the installed ones.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

SOURCE_DIR = Path(os.environ.get("UBERSIM_SOURCE_DIR") or Path(__file__).resolve().parents[2]).resolve()

# Run in a subprocess: loads a world, steps it, reports what it got and which files it mapped.
PROBE = """
import json, ubersim
world = ubersim.World("div-b", seed=7)
world.step(50)
with open("/proc/self/maps") as maps:
    mapped = sorted({line.split()[-1] for line in maps if "ubersim" in line.split()[-1]})
print(json.dumps({"file": ubersim.__file__, "hash": world.state_hash, "time": world.time, "mapped": mapped}))
"""


def build_dir():
    """The build tree: $UBERSIM_BUILD_DIR (set by ctest), else the parent of PYTHONPATH's python/."""
    if os.environ.get("UBERSIM_BUILD_DIR"):
        return Path(os.environ["UBERSIM_BUILD_DIR"]).resolve()
    for entry in os.environ.get("PYTHONPATH", "").split(os.pathsep):
        if entry and Path(entry).name == "python" and (Path(entry).parent / "CMakeCache.txt").is_file():
            return Path(entry).parent.resolve()
    pytest.skip("no build tree: set UBERSIM_BUILD_DIR (ctest does)")


def setuptools_leftovers(build):
    """What a setuptools build run in the checkout would leave there (build/ is CMake's tree)."""
    found = set(SOURCE_DIR.glob("*.egg-info")) | set(SOURCE_DIR.glob("apps/python/*.egg-info"))
    found |= set(build.glob("bdist.*")) | set(build.glob("lib.*"))
    found |= {p for p in (SOURCE_DIR / "dist", SOURCE_DIR / "build-pip") if p.exists()}
    return found


def clean_env(tmp):
    """An environment with nothing of ctest's or the build tree's in it; temporary files in TMP."""
    return {"PATH": "/usr/bin:/bin", "HOME": str(tmp), "TMPDIR": str(tmp), "LANG": "C.UTF-8"}


def hidden_run(command, hide, **kwargs):
    """COMMAND with the folders HIDE covered by empty ones in a private mount namespace, where one is
    allowed; else COMMAND as it is. Returns the finished process and whether the folders were hidden."""
    hide = [h for h in hide if not any(h != o and h.is_relative_to(o) for o in hide)]  # a parent hides its children
    unshare = shutil.which("unshare", path="/usr/bin:/bin")
    if unshare:
        mounts = " && ".join(f"mount -t tmpfs none '{h}'" for h in hide)
        wrapped = [unshare, "-rm", "/bin/sh", "-c", mounts + ' && exec "$@"', "sh"]
        if subprocess.run(wrapped + ["true"], capture_output=True).returncode == 0:
            return subprocess.run(wrapped + command, **kwargs), True
    return subprocess.run(command, **kwargs), False


@pytest.fixture
def tmp():
    folder = Path(tempfile.mkdtemp(prefix="ubersim-pip-test-")).resolve()
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def test_pip_install_offline_into_a_venv(tmp):
    build = build_dir()
    venv = tmp / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                          capture_output=True, text=True, env=clean_env(tmp))
    if made.returncode != 0:
        pytest.skip(f"cannot make a venv with {sys.executable} (python3-venv?): {made.stderr.strip()}")
    python = venv / "bin" / "python"
    if subprocess.run([python, "-m", "pip", "--version"], capture_output=True, env=clean_env(tmp)).returncode != 0:
        pytest.skip(f"no pip in a venv of {sys.executable} (python3-pip?)")

    before = setuptools_leftovers(build)
    env = dict(clean_env(tmp), UBERSIM_BUILD_DIR=str(build), UBERSIM_NO_BUILD="1")
    installed = subprocess.run(
        [python, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir",
         "--disable-pip-version-check", str(SOURCE_DIR)],
        capture_output=True, text=True, env=env, cwd=tmp, timeout=600)
    assert installed.returncode == 0, installed.stdout + installed.stderr
    assert setuptools_leftovers(build) == before, "the pip build wrote into the checkout or the build tree"

    run_dir = tmp / "run"
    run_dir.mkdir()
    reference = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, cwd=run_dir,
                               env=dict(clean_env(tmp), PYTHONPATH=str(build / "python")), timeout=300)
    assert reference.returncode == 0, reference.stderr
    expected = json.loads(reference.stdout)
    assert Path(expected["file"]).resolve().is_relative_to(build)

    hide = [d for d in (SOURCE_DIR, build) if not tmp.is_relative_to(d)]
    probe, hidden = hidden_run([str(python), "-c", PROBE], hide, capture_output=True, text=True, cwd=run_dir,
                               env=clean_env(tmp), timeout=300)
    where = "with the checkout and the build tree hidden" if hidden else "beside the checkout"
    assert probe.returncode == 0, (f"the installed package, run {where}, must find its own models/, schemas/ "
                                   f"(ubersim/share/ubersim) and plugins (ubersim/lib/ubersim/plugins):\n{probe.stderr}")
    got = json.loads(probe.stdout)
    site = venv.resolve()
    assert Path(got["file"]).resolve().is_relative_to(site), got["file"]
    assert got["mapped"], "no ÜberSim library mapped"
    outside = [f for f in got["mapped"] if not Path(f).is_relative_to(site)]
    assert not outside, f"libraries loaded from outside the venv: {outside}"
    assert any("/plugins/" in f for f in got["mapped"]), got["mapped"]
    assert (got["hash"], got["time"]) == (expected["hash"], expected["time"])
