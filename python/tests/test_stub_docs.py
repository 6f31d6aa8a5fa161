"""The stub's docstrings (eopnp/__init__.pyi, what an IDE shows) equal the runtime __doc__
(what help() shows, from the Rust doc comments): python/gen_stub_docs.py --check."""

import subprocess
import sys

from conftest import REPO


def test_stub_docstrings_equal_runtime_docs():
    out = subprocess.run(
        [sys.executable, str(REPO / "python" / "gen_stub_docs.py"), "--check"],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stdout + out.stderr
