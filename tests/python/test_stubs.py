"""The shipped type stubs match the compiled module (mypy's stubtest)."""

import subprocess
import sys


def test_stubs_match_the_module(tmp_path):
    # Run outside the checkout so that the installed package, with its stubs, is checked.
    r = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "vrpn", "--ignore-disjoint-bases"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
