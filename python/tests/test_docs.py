"""The Python snippets of the README and of docs/python.md run as shown, from the repository
root, and the package's docstring examples pass."""

from __future__ import annotations

import doctest
import os
import re
from pathlib import Path

import pytest

import rt_accel
from conftest import shared_meshes

ROOT = Path(__file__).resolve().parents[2]


def snippets(page: Path):
    blocks = re.findall(r"^```python\n(.*?)^```", page.read_text(), flags=re.S | re.M)
    return [(f"{page.name} snippet {i + 1}", code) for i, code in enumerate(blocks)]


SNIPPETS = snippets(ROOT / "README.md") + snippets(ROOT / "docs" / "python.md")


def test_the_pages_have_snippets():
    assert len(SNIPPETS) >= 4, SNIPPETS


@pytest.mark.parametrize("name,code", SNIPPETS, ids=[n for n, _ in SNIPPETS])
def test_snippet_runs(name, code, monkeypatch):
    shared_meshes()  # the snippets read the bunny
    monkeypatch.chdir(ROOT)
    # Run as a script runs, so that a snippet's `if __name__ == "__main__":` part runs too.
    exec(compile(code, name, "exec"), {"__name__": "__main__"})


def test_docstring_examples():
    result = doctest.testmod(rt_accel, verbose=False)
    assert result.attempted > 0 and result.failed == 0
