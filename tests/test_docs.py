"""The README stays a front page, its links lead somewhere, and the docs' Python runs.

The README is at most 300 lines (issue 20); every relative link of it names a file of the
repository (the documentation site itself is checked by ``mkdocs build --strict`` in
``.ci/run``); every page of ``mkdocs.yml``'s nav exists; and every ```` ```python ````
block of the README and of ``docs/`` runs, from the repository's root, without an
exception (one process for all, so the numba kernels compile once).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").rglob("*.md"))]


def test_the_readme_is_at_most_300_lines():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= 300, f"README.md has {n} lines; move detail into docs/"


def test_every_relative_link_of_the_readme_names_a_file():
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [u for u in links if not re.match(r"[a-z]+://", u)]
    assert len(local) >= 20
    missing = sorted({u for u in local if not (ROOT / u).exists()})
    assert not missing, f"README.md links to missing files: {missing}"


def _nav_files(node: object) -> list[str]:
    if isinstance(node, str):
        return [node] if node.endswith(".md") else []
    if isinstance(node, list):
        return [f for item in node for f in _nav_files(item)]
    if isinstance(node, dict):
        return [f for v in node.values() for f in _nav_files(v)]
    return []


def test_every_page_of_the_nav_exists_and_every_page_is_in_the_nav():
    conf = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    nav = _nav_files(conf["nav"])
    assert "guide/people.md" in nav and "plugins.md" in nav
    docs = ROOT / "docs"
    assert not [f for f in nav if not (docs / f).is_file()]
    pages = {str(p.relative_to(docs)) for p in docs.rglob("*.md")}
    assert pages == set(nav)


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


BLOCKS = [(p, i, code) for p in PAGES for i, code in enumerate(_python_blocks(p))]


def test_there_are_python_examples_to_run():
    assert len(BLOCKS) >= 6


def test_every_python_example_of_the_readme_and_the_docs_runs(tmp_path):
    """All blocks in one child process (the kernels compile once), the blocks of a page
    in sequence in one namespace (as a reader runs them), from the repository's root (the
    examples' paths are those of a clone)."""
    script = ["import traceback, sys", "failed = []", "pages = {}"]
    for path, i, code in BLOCKS:
        name = f"{path.relative_to(ROOT)}[{i}]"
        page = str(path.relative_to(ROOT))
        script += [f"try:\n    exec(compile({code!r}, {name!r}, 'exec'), "
                   f"pages.setdefault({page!r}, {{}}))",
                   f"except Exception:\n    failed.append({name!r}); traceback.print_exc()"]
    script += ["print('FAILED', failed) if failed else print('OK')",
               "sys.exit(1 if failed else 0)"]
    runner = tmp_path / "run_examples.py"
    runner.write_text("\n".join(script) + "\n")
    p = subprocess.run([sys.executable, str(runner)], capture_output=True, text=True,
                       cwd=ROOT, timeout=900)
    assert p.returncode == 0 and p.stdout.strip().endswith("OK"), p.stdout[-2000:] + p.stderr


@pytest.mark.parametrize("name", ["LICENSE", "CITATION.cff", "CHANGELOG.md"])
def test_the_project_files_exist(name):
    text = (ROOT / name).read_text(encoding="utf-8")
    assert len(text) > 200
