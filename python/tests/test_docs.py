"""The Python the README and docs/python.md show runs as written: each page's ```python blocks in
order, in one namespace, from a scratch folder that sees the repository's configs."""

import pathlib
import re

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
PAGES = [REPO / "README.md", REPO / "docs" / "python.md"]


def blocks(page: pathlib.Path):
    return re.findall(r"^```python\n(.*?)^```", page.read_text(), flags=re.S | re.M)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_the_pages_python_runs(page, in_tmp):
    (in_tmp / "configs").symlink_to(REPO / "configs")
    found = blocks(page)
    assert found, f"{page} shows no Python"
    namespace = {}
    for i, code in enumerate(found):
        exec(compile(code, f"{page.name}, block {i + 1}", "exec"), namespace)
