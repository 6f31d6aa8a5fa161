"""The Python README's examples (python/README.md, the package's page on PyPI) run as written:
every ```python block, in order, in one namespace, from the repository root; and the README
links nowhere outside python/ by a relative link (they would break on PyPI)."""

import os
import re

from conftest import REPO

README = REPO / "python" / "README.md"


def test_readme_examples(monkeypatch, capsys):
    text = README.read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 10
    monkeypatch.chdir(REPO)
    namespace = {}
    for k, code in enumerate(blocks):
        exec(compile(code, f"python/README.md (example {k + 1})", "exec"), namespace)
    assert "TooFewPoints 3 4" in capsys.readouterr().out
    assert os.getcwd() == str(REPO)


def test_readme_links_are_absolute():
    text = README.read_text()
    targets = re.findall(r"\]\(([^)]+)\)", text) + re.findall(r"<(https?://[^>]+)>", text)
    assert targets
    for target in targets:
        assert re.match(r"https?://", target), target


def test_repository_readme_example(monkeypatch):
    """The repository README's short Python example (its "## Python" section) runs as written."""
    text = (REPO / "README.md").read_text()
    section = text[text.index("\n## Python\n"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(REPO)
    exec(compile(code, "README.md (Python example)", "exec"), {})
