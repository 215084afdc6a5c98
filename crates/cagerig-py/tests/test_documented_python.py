"""Every ```python block of the README and docs/*.md runs as written, from a folder laid out
like the repository's root (its data/ and examples/ linked, an empty out/ to write into)."""

import os
import re
import warnings

import pytest

from conftest import REPO

DOCUMENTS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
BLOCKS = [
    pytest.param(block, id=f"{doc.name}:{text[: match.start()].count(chr(10)) + 2}")
    for doc in DOCUMENTS
    for text in [doc.read_text(encoding="utf-8")]
    for match in re.finditer(r"```python\n(.*?)```", text, re.S)
    for block in [match.group(1)]
]


def test_the_docs_have_python_blocks():
    assert len(BLOCKS) >= 1


@pytest.mark.parametrize("block", BLOCKS)
def test_documented_python_block_runs(block, tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    for linked in ("data", "examples"):
        os.symlink(REPO / linked, tmp_path / linked)
    (tmp_path / "out").mkdir()
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Arm's own files warn (renormalised rows)
        exec(compile(block, "<documented block>", "exec"), {"__name__": "__documented__"})
    # What the block says it writes is there.
    for written in re.findall(r"[\"'](out/[^\"']+)[\"']", block):
        assert (tmp_path / written).is_file(), written
