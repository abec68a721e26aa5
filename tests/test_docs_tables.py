"""The docs' generated tables (``scripts/docs_tables.py``) say what their sources say: each table
between its markers is exactly what its JSON in ``docs/data/`` or its declaration in the code gives."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
_spec = importlib.util.spec_from_file_location("docs_tables", ROOT / "scripts" / "docs_tables.py")
docs_tables = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(docs_tables)


@pytest.mark.parametrize("name", sorted(docs_tables.TABLES))
def test_a_docs_table_matches_its_source(name):
    path, text, expected = docs_tables.rendered(name)
    assert text == expected, f"{path.name}: table '{name}' is out of date: run python scripts/docs_tables.py {name}"


def test_a_changed_table_is_noticed(tmp_path, monkeypatch):
    """A number edited by hand in a table is found (the check compares the whole table)."""
    name = "photo-outfits"
    doc, rows = docs_tables.TABLES[name]
    copy = tmp_path / "docs" / Path(doc).name
    copy.parent.mkdir()
    copy.write_text((ROOT / doc).read_text().replace(rows()[2], rows()[2].replace("|", "| 9", 1), 1))
    monkeypatch.setattr(docs_tables, "ROOT", tmp_path)
    monkeypatch.setitem(docs_tables.TABLES, name, (f"docs/{copy.name}", rows))
    _, text, expected = docs_tables.rendered(name)
    assert text != expected and rows()[2] in expected
