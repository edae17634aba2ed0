"""docs/equations.md: every listed symbol exists and its docstring cites what it implements."""

import importlib
import re
from pathlib import Path

import pytest

EQUATIONS = Path(__file__).resolve().parents[1] / "docs" / "equations.md"
ROW = re.compile(r"^\| (?P<label>[^|]+) \| [^|]+ \| (?P<code>.+) \|$")
SYMBOL = re.compile(r"\[`(?P<symbol>[\w.]+)`\]\((?P<path>[^)]+)\)")


def _rows() -> list[tuple[str, str, str]]:
    rows = []
    for line in EQUATIONS.read_text().splitlines():
        match = ROW.match(line)
        if match is None or match["label"].strip() in ("thesis", "---"):
            continue
        for symbol in SYMBOL.finditer(match["code"]):
            rows.append((match["label"].strip(), symbol["symbol"], symbol["path"]))
    return rows


def _resolve(dotted: str) -> object:
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            target: object = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attribute in parts[i:]:
            target = getattr(target, attribute)
        return target
    raise ImportError(dotted)


def _citations(label: str) -> list[str]:
    """What a docstring must mention: "3.20" for "(3.20)", "Table 4.1" for "Table 4.1"."""
    named = re.findall(r"(?:Table|Fig\.|Section) [\d.]*\d", label)
    rest = re.sub(r"(?:Table|Fig\.|Section) [\d.]*\d", "", label)
    return named + re.findall(r"\d\.\d+", rest)


def test_the_map_lists_the_key_equations():
    labels = " ".join(label for label, _, _ in _rows())
    for needed in ("(3.20)", "(4.7)", "(4.11)", "(4.14)", "(4.9)", "Fig. 3.4"):
        assert needed in labels


@pytest.mark.parametrize(("label", "symbol", "path"), _rows())
def test_each_symbol_exists_and_cites_its_equation(label, symbol, path):
    target = _resolve(symbol)
    assert (EQUATIONS.parent / path).resolve().is_file(), f"{path} does not exist"
    doc = " ".join((getattr(target, "__doc__", None) or "").split())
    for citation in _citations(label):
        pattern = re.escape(citation) + r"(?!\d)"
        assert re.search(pattern, doc), f"{symbol}'s docstring does not cite {citation}"
