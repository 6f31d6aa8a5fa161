"""The cluster example (python/examples/cluster_register.py) runs on a Dask LocalCluster of two
worker processes and its results equal the serial ones (skipped where dask.distributed is not
installed; scripts/test.sh installs it and sets EOPNP_REQUIRE_PEERS=1, under which its absence is
an error)."""

import subprocess
import sys

from conftest import REPO, require


def test_cluster_register_example():
    require("dask.distributed")
    example = REPO / "python" / "examples" / "cluster_register.py"
    out = subprocess.run(
        [sys.executable, str(example), "--workers", "2", "--copies", "10", "--partitions", "4"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 differ from the serial results" in out.stdout
