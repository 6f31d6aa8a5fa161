"""The README's Python example runs as written (from the repository root)."""

import os
import re

from conftest import REPO


def test_readme_example(monkeypatch, capsys):
    text = (REPO / "README.md").read_text()
    section = text[text.index("\n## Python\n"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(REPO)
    exec(compile(code, "README.md (Python example)", "exec"), {})
    assert "TooFewPoints 3 4" in capsys.readouterr().out
    assert os.getcwd() == str(REPO)
