"""The type stubs (eopnp/__init__.pyi) match the runtime module: mypy's stubtest (installed by
scripts/test.sh; skipped where mypy is not installed, an error under EOPNP_REQUIRE_PEERS=1)."""

import subprocess
import sys

from conftest import require


def test_stubtest():
    require("mypy.stubtest")
    out = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "eopnp"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stdout + out.stderr
