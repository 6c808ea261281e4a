"""Griffe extension: render the package's plain-text docstrings as Markdown.

The docstrings are Google style and written to be read in the source, with two
habits that Markdown reads differently:

* Sphinx roles (``:func:`plan```, ``:mod:`jaxspline.screen.pairs```) would show up
  verbatim. A role whose target is documented in the API reference becomes a link to
  its entry in the API reference (docs/api/*.md); any other role becomes inline code.
* Shapes and units in adjacent brackets (``float [M, 3] [m/s]``) are a Markdown
  reference link (text ``M, 3``, label ``m/s``): the second bracket is escaped.
* Sections follow each other without a blank line (``Args:`` ... ``Returns:`` ...
  ``Raises:``), which Google style allows and Griffe's parser does not: a blank line
  is put above every section title that has an indented line below it.

Inspected objects that have no docstring of their own get their type's: a constant
``MU_EARTH = 3.986004418e14`` would read "Convert a string or number to a floating point
number", a NamedTuple field "Alias for field number 0". Those are dropped, so a
constant shows its value and a class's ``Attributes`` section describes its fields.
Only the rendered text changes, never the source.
"""

from __future__ import annotations

import importlib
import inspect
import pathlib
import re

import griffe

ROLE = re.compile(r":(?:func|mod|class|meth|attr|data|obj|exc|const):`~?([^`]+)`")
ADJACENT = re.compile(r"\](\s?)\[")
CODE = re.compile(r"(`+)(?:.|\n)*?\1")  # inline code spans, left untouched
FIELD_ALIAS = re.compile(r"^Alias for field number \d+$")
SECTION = re.compile(
    r"^(Args|Arguments|Parameters|Returns|Yields|Raises|Attributes|Examples?|Notes?|"
    r"Warns|Warnings?|References?|See Also|Other Parameters):\s*$"
)
TYPE_DOCS = {
    inspect.cleandoc(t.__doc__)
    for t in (
        bool,
        int,
        float,
        complex,
        str,
        bytes,
        tuple,
        list,
        dict,
        set,
        frozenset,
        type(None),
        pathlib.Path,
        pathlib.PurePath,
        type(pathlib.Path()),
    )
    if t.__doc__
}


API_PAGES = pathlib.Path(__file__).resolve().parents[1] / "api"


def _resolve(path: str):
    """The object a dotted ``path`` names (module, then attributes), or None."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _documented() -> dict[object, str]:
    """Where the API reference documents each object: ``id(obj)`` (functions, classes,
    modules) or the path itself (constants, whose values may be shared) -> its path."""
    out: dict[object, str] = {}
    for page in sorted(API_PAGES.glob("*.md")):
        for path in re.findall(r"^::: ([\w.]+)", page.read_text(), flags=re.M):
            obj = _resolve(path)
            key = id(obj) if callable(obj) or inspect.ismodule(obj) else path
            out.setdefault(key, path)
    return out


def _target(path: str, documented: dict[object, str]) -> str | None:
    """The documented path of the object ``path`` names (``plan`` is ``jaxspline.plan``)."""
    full = path if path.startswith("jaxspline") else f"jaxspline.{path}"
    if full in documented:
        return documented[full]
    obj = _resolve(full)
    if obj is None or not (callable(obj) or inspect.ismodule(obj)):
        return None
    return documented.get(id(obj))


def _blank_above_sections(text: str) -> str:
    lines = text.split("\n")
    out: list[str] = []
    for i, line in enumerate(lines):
        below = lines[i + 1] if i + 1 < len(lines) else ""
        if SECTION.match(line) and out and out[-1].strip() and below.startswith(" "):
            out.append("")
        out.append(line)
    return "\n".join(out)


def markdown_text(text: str, documented: dict[object, str]) -> str:
    """The docstring ``text`` with roles resolved, adjacent brackets escaped and a blank
    line above every section title."""
    text = _blank_above_sections(text)

    def role(m: re.Match) -> str:
        path = m.group(1).strip()
        target = _target(path, documented)
        return f"[`{path}`][{target}]" if target else f"`{path}`"

    out, last = [], 0
    for m in CODE.finditer(text):  # escape brackets outside code spans only
        out.append(ADJACENT.sub(r"]\1\\[", text[last : m.start()]))
        out.append(m.group(0))
        last = m.end()
    out.append(ADJACENT.sub(r"]\1\\[", text[last:]))
    return ROLE.sub(role, "".join(out))


class MarkdownDocstrings(griffe.Extension):
    """Rewrites every docstring's text once the object tree is complete."""

    def __init__(self) -> None:
        self._documented = _documented()

    def on_object(self, *, obj: griffe.Object, **kwargs) -> None:
        doc = obj.docstring
        if doc is None:
            return
        if FIELD_ALIAS.match(doc.value.strip()) or inspect.cleandoc(doc.value) in TYPE_DOCS:
            obj.docstring = None
            return
        doc.value = markdown_text(doc.value, self._documented)
