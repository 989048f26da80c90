# SPDX-License-Identifier: Apache-2.0
# The example scripts of docs/python.md run as documented (briefly), so that they do not rot.
import os
import re
import subprocess
import sys

SOURCE = os.environ.get("UBERSIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def test_random_actions_prints_env_steps_per_second():
    script = os.path.join(SOURCE, "examples", "python", "random_actions.py")
    out = subprocess.run([sys.executable, script, "--num-envs", "4", "--steps", "20"], capture_output=True, text=True,
                         check=True).stdout
    match = re.search(r"4 worlds, 80 env steps .* ([0-9]+) env steps/s", out)
    assert match and int(match.group(1)) > 0, out


def test_env_bench_finds_the_env_and_the_kernel_in_the_same_state():
    script = os.path.join(SOURCE, "tools", "env_bench.py")
    out = subprocess.run([sys.executable, script, "--num-envs", "2", "--duration", "0.5", "--repeat", "1"], capture_output=True,
                         text=True).stdout
    assert "final state hashes agree" in out, out


def test_the_example_of_docs_python_md_runs():
    # The 20-line example as the page shows it, run as it is.
    text = open(os.path.join(SOURCE, "docs", "python.md")).read()
    code = text.split("```python\nimport numpy as np", 1)[1].split("```", 1)[0]
    out = subprocess.run([sys.executable, "-c", "import numpy as np" + code], capture_output=True, text=True,
                         check=True).stdout
    finished = int(re.search(r"(-?[0-9]+) episodes finished", out).group(1))
    assert finished > 64, out  # the controller solves GoToBall: many episodes in 25 s of each world
