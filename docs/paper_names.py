"""Griffe extension for the API reference: the docstrings name the papers and the project's
design notes by short internal keys ("seed 000", "DESIGN.md"); the reader gets the papers'
authors and year instead (full citations on the References page).

Delete this file (and its line in mkdocs.yml) once the docstrings cite the papers themselves.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

# Longest first: "seeds 000, 001" before "seed 000".
_REPLACEMENTS = [
    (r"\bseeds 000, 001\b", "Xia et al. 2014; Yu et al. 2019"),
    (r"\b[Ss]eed 000\b", "Xia et al. 2014"),
    (r"\b[Ss]eed 001\b", "Yu et al. 2019"),
    (r"\b[Ss]eed 004\b", "Nguyen-Quoc et al."),
    (r" \(DESIGN\.md contract\)", ""),
    (r"\(DESIGN\.md contract: ", "("),
    (r"\(DESIGN\.md: ", "("),
    (r"\(DESIGN\.md,? errata\)", "(see the Theory page)"),
    (r" \(DESIGN\.md\)", ""),
    (r"[Tt]he contract's JSON object", "The JSON answer"),
    (r"the contract's ``assumptions``", "``assumptions``"),
    (r"the contract's plain CSV", "a plain CSV"),
    (r"its name before the contract's was used", "its earlier name"),
    (r"the contract's name", "that name"),
    (r"\b[Tt]he contract's\b", "the documented"),
    (r"\bDESIGN\.md\b", "the Theory page"),
]
_COMPILED = [(re.compile(pattern), text) for pattern, text in _REPLACEMENTS]


def _cite(text: str) -> str:
    for pattern, replacement in _COMPILED:
        text = pattern.sub(replacement, text)
    return text


class PaperNames(griffe.Extension):
    """Rewrite the internal keys in every docstring of a loaded package."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if obj.docstring is not None:
                obj.docstring.value = _cite(obj.docstring.value)
            stack.extend(member for member in obj.members.values() if not member.is_alias)
