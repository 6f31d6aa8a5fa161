"""The type stubs (eopnp/__init__.pyi) match the runtime module: mypy's stubtest (installed by
scripts/test.sh; skipped where mypy is not installed)."""

import subprocess
import sys

import pytest


def test_stubtest():
    pytest.importorskip("mypy.stubtest")
    out = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "eopnp"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stdout + out.stderr
