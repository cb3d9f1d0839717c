"""The scenario reference, generated from the dataclasses themselves.

Every field of :class:`~deburr_drake.config.Scenario` by its dotted name
(a list of dataclasses as ``process.burrs[].height``), with its type, unit,
package default, the ``paper`` scenario's value, the allowed range and one
line of meaning. Nothing here is written by hand:

- **unit and meaning** come from the field's comment in the source, by the
  convention every config dataclass follows::

      name: type = default  # UNIT, one line of meaning

  UNIT comes first, then ``,`` ``;`` ``:`` or ``.`` and the meaning. A field
  whose statement spans lines takes the comment on any of its lines; a
  comment block directly above the field (no blank line between) is read
  when the statement has none, and gives the meaning when the trailing
  comment is the unit alone. UNIT is an SI expression (``m``, ``N s/m``,
  ``m/(N s)``, ``1/s``, ``N m s/rad``, ``N or N m``), a list of them in
  brackets for a list field whose elements differ (``[N, N/m, N s/m]``), or
  ``-`` for a dimensionless number, a name, a switch or a count.
  :func:`convention_problems` names every field that breaks this
  (``tests/config/test_reference.py`` fails on it);
- **the allowed range** is what ``Scenario.validate()`` says: each field is
  set in turn to values that are out of any sensible range (NaN, negative,
  huge, an unknown name, a wrong length) and the ``allowed ...`` part of
  every :class:`ConfigError` naming that field is kept;
- **defaults** are ``Scenario()``'s and ``load_scenario("paper")``'s.

:func:`scenario_reference_markdown` writes the page the docs build includes
(``docs/conf.py`` calls :func:`write_scenario_reference`).
"""

import ast
import copy
import dataclasses
from dataclasses import dataclass
from functools import lru_cache
import inspect
import io
import itertools
import math
import re
import textwrap
import tokenize
import typing
from typing import Dict, List, Optional, Tuple

from deburr_drake.config.checks import ConfigError
from deburr_drake.config.control import ControllerConfig
from deburr_drake.config.scenario import Scenario, load_scenario

__all__ = [
    "FieldDoc",
    "field_comments",
    "split_unit",
    "is_unit",
    "scenario_fields",
    "convention_problems",
    "scenario_reference_markdown",
    "write_scenario_reference",
]

_ATOM = r"(?:m|s|N|rad|kg|Pa|Hz|J|W)(?:\^-?\d)?"
_PRODUCT = rf"{_ATOM}(?: {_ATOM})*"
_FACTOR = rf"(?:{_PRODUCT}|\({_PRODUCT}\))"
_QUOTIENT = rf"(?:1|{_FACTOR})(?:(?:/| per ){_FACTOR})*"
_UNIT = rf"{_QUOTIENT}(?: or {_QUOTIENT})*"
_UNIT_RE = re.compile(rf"-|{_UNIT}|\[{_UNIT}(?:, {_UNIT})*\]")


def is_unit(text: str) -> bool:
    """Whether ``text`` is a unit by the convention (see the module)."""
    return _UNIT_RE.fullmatch(text) is not None


def split_unit(comment: str) -> Tuple[str, str]:
    """``"m/s, the feed"`` -> ``("m/s", "the feed")``; ``("", comment)``
    when the comment does not start with a unit."""
    comment = comment.strip()
    if comment.startswith("["):
        head, sep, rest = comment.partition("]")
        head += sep
    else:
        m = re.match(r"(.*?)(?:[,;:.](?:\s|$)|$)", comment)
        head, rest = m.group(1), comment[m.end() :]
    head = head.strip()
    if not is_unit(head):
        return "", comment
    return head, rest.lstrip(" ,;:.").strip()


@dataclass
class _Comment:
    trailing: str  # the comment on the field's statement
    block: str  # the comment lines directly above it
    line: int  # the statement's first line in its file


@lru_cache(maxsize=None)
def field_comments(cls) -> Dict[str, _Comment]:
    """The comments of each annotated field of the dataclass ``cls``, read
    from its source with ``tokenize`` and ``ast``."""
    lines, first = inspect.getsourcelines(cls)
    source = textwrap.dedent("".join(lines))
    comments = {}  # line (1-based, in source) -> text
    code_lines = set()
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string.lstrip("#").strip()
        elif tok.type not in (
            tokenize.NL,
            tokenize.NEWLINE,
            tokenize.INDENT,
            tokenize.DEDENT,
            tokenize.ENDMARKER,
        ):
            code_lines.update(range(tok.start[0], tok.end[0] + 1))
    (node,) = ast.parse(source).body
    found = {}
    for stmt in node.body:
        if not (
            isinstance(stmt, ast.AnnAssign)
            and isinstance(stmt.target, ast.Name)
        ):
            continue
        trailing = " ".join(
            comments[n]
            for n in range(stmt.lineno, stmt.end_lineno + 1)
            if n in comments
        )
        block = []
        n = stmt.lineno - 1
        while n in comments and n not in code_lines:
            block.insert(0, comments[n])
            n -= 1
        found[stmt.target.id] = _Comment(
            trailing, " ".join(block), first + stmt.lineno - 1
        )
    return found


@dataclass
class FieldDoc:
    """One row of the scenario reference."""

    path: str  # dotted name; a list of dataclasses as name[].field
    type: str  # float, int, bool, str, List[float], ...
    unit: str  # by the convention; "" when the comment gives none
    meaning: str  # one line; "" when the comment gives none
    detail: str  # the comment past its first sentence
    default: object  # Scenario()'s value
    paper: object  # load_scenario("paper")'s value
    allowed: str  # what validate() allows
    source: str  # file:line of the field


def _first(text: str):
    """(first sentence, "", the rest) of ``text``."""
    parts = re.split(r"(?<=[a-z0-9)]\.)\s+(?=[A-Z0-9(])", text, maxsplit=1)
    return parts[0].strip(), "", (parts[1].strip() if len(parts) > 1 else "")


def _type_name(hint) -> str:
    origin = typing.get_origin(hint)
    if origin in (list, List):
        (item,) = typing.get_args(hint)
        return f"List[{_type_name(item)}]"
    return getattr(hint, "__name__", str(hint))


_MESSAGE = re.compile(
    r"^(?P<name>\S+) = .* is invalid: allowed (?P<a>.*)$", re.S
)


def _probes(hint, value):
    """Values of type ``hint`` out of any sensible range."""
    if hint is bool:
        return []
    if hint is float:
        return [math.nan, -1.0, 0.0, -1e300, 1e300]
    if hint is int:
        return [-1, 0, 10**9, 1.5]
    if hint is str:
        return ["\x01not a value"]
    if typing.get_origin(hint) in (list, List):
        (item,) = typing.get_args(hint)
        probes = [[]] if value else []
        base = list(value) if value else [_probes(item, None)[0]]
        for p in _probes(item, None):
            probes.append([p] + base[1:])
        probes.append(base + base[-1:])
        if item is int:
            probes.append([base[0], base[0]])
        return probes
    return []


def _allowed(scenario, path: str, hint, owner, name: str) -> str:
    """The ``allowed ...`` texts of validate() for the field ``path``: the
    field (of the object ``owner(scenario)``) set to each probe in turn."""
    if hint is bool:
        return "true or false"
    base = copy.deepcopy(scenario)
    owner(base)  # makes the element of a list of dataclasses
    owner_path = path.rsplit(".", 1)[0]
    for _ in range(5):  # a new list element's defaults may be invalid
        try:
            base.validate()
            break
        except ConfigError as e:
            m = _MESSAGE.match(str(e))
            bad = m and re.sub(r"\[\d+\]", "[]", m["name"])
            if not (bad and bad.rsplit(".", 1)[0] == owner_path):
                break
            setattr(owner(base), bad.rsplit(".", 1)[1], 1.0)
    found = []
    # A control law's fields are validated only with that law chosen.
    kinds = ControllerConfig.KINDS if path.startswith("controller.") else [None]
    for kind, probe in itertools.product(
        kinds, _probes(hint, getattr(owner(base), name))
    ):
        trial = copy.deepcopy(base)
        if kind is not None:
            trial.controller.kind = kind
        setattr(owner(trial), name, probe)
        try:
            trial.validate()
        except ConfigError as e:
            m = _MESSAGE.match(str(e))
            if (
                m
                and re.sub(r"\[\d+\]", "[]", m["name"]) in (path, path + "[]")
                and m["a"] not in found
            ):
                found.append(m["a"])
        except (TypeError, ValueError, AttributeError, IndexError):
            pass
    return "; ".join(found)


def _walk(cls, prefix: str, default, paper, scenario, owner):
    """FieldDocs of the fields of ``cls``, whose instance in a scenario is
    ``owner(scenario)``."""
    hints = typing.get_type_hints(cls)
    comments = field_comments(cls)
    module = inspect.getsourcefile(cls)
    for f in dataclasses.fields(cls):
        path = f"{prefix}{f.name}"
        hint = hints[f.name]
        if dataclasses.is_dataclass(hint):
            yield from _walk(
                hint,
                path + ".",
                getattr(default, f.name),
                getattr(paper, f.name),
                scenario,
                lambda obj, o=owner, n=f.name: getattr(o(obj), n),
            )
            continue
        args = typing.get_args(hint)
        if typing.get_origin(hint) in (list, List) and dataclasses.is_dataclass(
            args[0]
        ):
            # A list of dataclasses: one row per field of its element,
            # probed on a list of one default element.
            def element(obj, o=owner, n=f.name, item=args[0]):
                items = getattr(o(obj), n)
                if not items:
                    items.append(item())
                return items[0]

            papers = getattr(paper, f.name)
            for doc in _walk(
                args[0], path + "[].", args[0](), args[0](), scenario, element
            ):
                doc.paper = [
                    getattr(p, doc.path.rsplit(".", 1)[1]) for p in papers
                ]
                yield doc
            continue
        c = comments.get(f.name, _Comment("", "", 0))
        unit, text = split_unit(c.trailing or c.block)
        if not text and c.trailing and c.block:
            text = split_unit(c.block)[1] or c.block
        # One line: the first sentence; the rest is the detail.
        meaning, _, rest = _first(text)
        detail = rest
        yield FieldDoc(
            path=path,
            type=_type_name(hint),
            unit=unit,
            meaning=meaning,
            detail=detail,
            default=getattr(default, f.name),
            paper=getattr(paper, f.name),
            allowed=_allowed(scenario, path, hint, owner, f.name),
            source=f"{module}:{c.line}",
        )


def scenario_fields(paper: Optional[Scenario] = None) -> List[FieldDoc]:
    """Every leaf field of :class:`Scenario`, in declaration order."""
    if paper is None:
        paper = load_scenario("paper")
    return list(
        _walk(Scenario, "", Scenario(), paper, Scenario(), lambda obj: obj)
    )


def convention_problems(fields: Optional[List[FieldDoc]] = None) -> List[str]:
    """One line per field whose comment breaks the convention."""
    problems = []
    for doc in fields if fields is not None else scenario_fields():
        missing = [
            what
            for what, text in (("a unit", doc.unit), ("a meaning", doc.meaning))
            if not text
        ]
        if missing:
            problems.append(
                f"{doc.path} ({doc.source}) has no "
                f"{' and no '.join(missing)}: write "
                "'name: type = default  # UNIT, meaning'"
            )
    return problems


def _shown(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"' if value else '""'
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, list):
        if value and dataclasses.is_dataclass(value[0]):
            return f"{len(value)} entries"
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    return str(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def scenario_reference_markdown() -> str:
    """The reference page (MyST Markdown): one table per section."""
    fields = scenario_fields()
    sections: Dict[str, List[FieldDoc]] = {}
    for doc in fields:
        sections.setdefault(doc.path.split(".")[0].split("[")[0], []).append(
            doc
        )
    out = _reference_intro(len(fields))
    for section, docs in sections.items():
        out += _section_table(section, docs)
    out += _WRITING_A_FIELD
    return "\n".join(out)


def _reference_intro(n_fields: int) -> List[str]:
    """The page's title and introduction."""
    return [
        "# Scenario reference",
        "",
        "Generated from the dataclasses in `deburr_drake/config/` by "
        "`deburr_drake.config.reference` at every docs build: every field "
        f"of `Scenario` ({n_fields} fields), by the dotted name that "
        "`--scenario-text`, `--set`, `set_field` and the study files use "
        "(`process.burrs[].height`: each element of a list; index it as "
        "`process.burrs[0].height`). *default* is the package's "
        "(`Scenario()`, the `point_mass` cell), followed by the `paper` "
        'scenario\'s (`load_scenario("paper")`) where that differs. '
        "*Allowed* is what `validate()` accepts (a bad value is one "
        "`ConfigError` line naming the field); none given: any value of "
        "the type. SI units throughout (`-`: no unit).",
        "",
        "The unit and meaning come from each field's comment "
        "(`name: type = default  # UNIT, meaning`; see "
        "[writing a field](#writing-a-field)).",
        "",
    ]


def _section_table(section: str, docs: List[FieldDoc]) -> List[str]:
    """One section's heading, docstring, table of fields and notes."""
    out = []
    out.append(f"## `{section}`")
    out.append("")
    cls = type(getattr(Scenario(), section))
    if dataclasses.is_dataclass(cls) and cls.__doc__:
        out.append(" ".join(cls.__doc__.split()))
        out.append("")
    out.append("| field (type) | unit | default | meaning; *allowed* |")
    out.append("|---|---|---|---|")
    for d in docs:
        default = f"`{_shown(d.default)}`"
        if _shown(d.paper) != _shown(d.default):
            default += f"; paper `{_shown(d.paper)}`"
        allowed = f" *Allowed:* {d.allowed}." if d.allowed else ""
        out.append(
            "| "
            + " | ".join(
                _cell(x)
                for x in (
                    f"`{d.path}` ({d.type})",
                    d.unit,
                    default,
                    (d.meaning.rstrip(".") + "." if allowed else d.meaning)
                    + allowed,
                )
            )
            + " |"
        )
    out.append("")
    notes = [d for d in docs if d.detail]
    if notes:
        out.append("Notes from the source:")
        out.append("")
        for d in notes:
            out.append(f"- `{d.path}`: {d.meaning} {d.detail}")
        out.append("")
    return out


_WRITING_A_FIELD = [
    "## Writing a field",
    "",
    "A new field is documented by its comment, which this page and the "
    "tests read:",
    "",
    "```python",
    "cutoff_frequency: float = 20.0  # Hz, first-order low-pass of the reading",
    "```",
    "",
    "The comment starts with the unit: an SI expression (`m`, `N s/m`, "
    "`m/(N s)`, `1/s`, `N or N m`), a bracketed list for a list whose "
    "elements differ (`[N, N/m, N s/m]`), or `-` for a dimensionless "
    "number, a name, a switch or a count; then `,` `;` `:` or `.` and "
    "one line of meaning. A longer explanation goes in a comment block "
    "directly above the field; a field with only that block takes its "
    "unit and meaning from the block's first words. The range is "
    "checked in the class's `validate()` with the helpers of "
    "`deburr_drake/config/checks.py`, whose `allowed ...` text this "
    "page shows. `tests/config/test_reference.py` names every field "
    "without a unit or a meaning and checks that this page lists every "
    "field of `Scenario`.",
    "",
]


def write_scenario_reference(path) -> str:
    """Writes :func:`scenario_reference_markdown` to ``path`` (only when
    it changed, so the docs build does not re-read it); returns it."""
    from pathlib import Path

    text = scenario_reference_markdown()
    path = Path(path)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return text
