"""The cluster example (python/examples/cluster_register.py) runs on a Dask LocalCluster of two
worker processes and its results equal the serial ones (skipped where dask.distributed is not
installed; scripts/test.sh installs it)."""

import subprocess
import sys

import pytest

from conftest import REPO


def test_cluster_register_example():
    pytest.importorskip("dask.distributed")
    example = REPO / "python" / "examples" / "cluster_register.py"
    out = subprocess.run(
        [sys.executable, str(example), "--workers", "2", "--copies", "10", "--partitions", "4"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 differ from the serial results" in out.stdout
