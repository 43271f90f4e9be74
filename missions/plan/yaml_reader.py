"""The plan's first pass: untrusted YAML -> plain Python values, with where each value and key was written.

    data, yaml_doc = parse_yaml(text, "survey.yaml", problems)   # data None: the problems say why
    yaml_doc.where(("mission", 1, "survey", "altitude_m"))       # "survey.yaml:14:19"

PyYAML's safe composer (no object construction, no custom tags) gives nodes with line/column; we convert them
ourselves with a depth cap and a node budget (an alias bomb expands through the budget, not through memory),
reject duplicate keys (PyYAML silently keeps the last) and read only `true`/`false` as booleans (YAML 1.1 turns
`off`, an isotherm mode, into False). Problems are collected, not raised: the later passes add theirs.
"""

from __future__ import annotations

import math
import re
from typing import Any

import yaml

from cdf.errors import ECHO_CHARS, clip, shown
from missions.errors import Problem

MAX_NODES = 200_000             # YAML nodes after alias expansion
MAX_DEPTH = 40

# A number with an exponent as YAML 1.2 writes it (1e-9, 2E5, 1.0e308), which YAML 1.1 resolves as text.
_EXPONENT_NUMBER = re.compile(r"[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)[eE][-+]?[0-9]+")

_TOO_DEEP_HINT = "a plan nests a few levels deep; look for unclosed brackets or runaway indentation"
_SYNTAX_HINT = "check indentation, colons and quotes"


class _Budget(Exception):
    pass


class PositionedYaml:
    """Node tree -> plain Python values, recording where every value and key is; `problems` collects what every
    pass finds wrong in the plan, each located where it is written."""

    def __init__(self, file: str, problems: list[Problem]) -> None:
        self.file = file
        self.problems = problems
        self.values: dict[tuple, tuple[int, int]] = {}
        self.keys: dict[tuple, tuple[int, int]] = {}
        # values already reported here and read as None (.inf, a YAML tag): the schema pass skips them,
        # or `name: .inf` would also be "name must be text, got nothing"
        self.reported: set[tuple] = set()
        self.quoted: set[tuple] = set()     # values written in quotes: "remove the quotes" is a fix only there
        self.nodes = 0

    def loc(self, mark: Any) -> str:
        return f"{self.file}:{mark.line + 1}:{mark.column + 1}"

    def where(self, path: tuple, key: bool = False) -> str:
        """file:line:col of the value at `path` (of its key with key=True), or of its deepest located parent."""
        table = self.keys if key else self.values
        p = tuple(path)
        while p:
            if p in table:
                line, col = table[p]
                return f"{self.file}:{line + 1}:{col + 1}"
            p = p[:-1]
        return self.file

    def report(self, path: tuple, message: str, hint: str | None, key: bool = False) -> None:
        """A problem with the value at `path` (with its key, key=True), located where it is written."""
        self.problems.append(Problem(self.where(path, key), message, hint, path=tuple(path)))

    def convert(self, node: Any, path: tuple, depth: int = 0) -> Any:
        self.nodes += 1
        if self.nodes > MAX_NODES:
            raise _Budget(f"the YAML expands to more than {MAX_NODES} nodes (aliases?)")
        if depth > MAX_DEPTH:
            raise _Budget(f"the YAML is nested deeper than {MAX_DEPTH} levels")
        self.values.setdefault(path, (node.start_mark.line, node.start_mark.column))
        if isinstance(node, yaml.MappingNode):
            return self.mapping(node, path, depth)
        if isinstance(node, yaml.SequenceNode):
            return [self.convert(v, path + (i,), depth + 1) for i, v in enumerate(node.value)]
        return self.scalar(node, path)

    def mapping(self, node: Any, path: tuple, depth: int) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for knode, vnode in node.value:
            if not isinstance(knode, yaml.ScalarNode) or knode.tag == "tag:yaml.org,2002:merge":
                what = "merge keys (<<)" if isinstance(knode, yaml.ScalarNode) else "complex keys"
                self.problems.append(Problem(self.loc(knode.start_mark), f"{what} are not supported",
                                             "write the keys out", path=path))
                continue
            key = knode.value
            if key in out:
                self.problems.append(Problem(self.loc(knode.start_mark), f"duplicate key {shown(key)}",
                                             "YAML keeps only the last one; remove one of them", path=path))
                continue
            self.keys[path + (key,)] = (knode.start_mark.line, knode.start_mark.column)
            out[key] = self.convert(vnode, path + (key,), depth + 1)
        return out

    def scalar(self, node: Any, path: tuple) -> Any:
        tag, text = node.tag, node.value
        if node.style in ("'", '"'):
            self.quoted.add(path)
        if node.style is None and tag == "tag:yaml.org,2002:str" and _EXPONENT_NUMBER.fullmatch(text):
            # YAML 1.1 reads 1e-9 and 1.0e308 (no dot, or no sign in the exponent) as text, YAML 1.2 and
            # every editor as numbers: read them as numbers, as booleans are read the YAML 1.2 way
            return self.number(float(text), text, node, path)
        if tag == "tag:yaml.org,2002:str" or node.style in ("'", '"', "|", ">"):
            return text
        if tag == "tag:yaml.org,2002:null":
            return None
        if tag == "tag:yaml.org,2002:bool":
            # YAML 1.1 booleans yes/no/on/off stay text: `alarm_mode: off` means the option "off".
            return {"true": True, "false": False}.get(text.lower(), text)
        if tag in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float"):
            return self.resolved_number(node, path)
        if tag == "tag:yaml.org,2002:timestamp":
            return text
        self.problems.append(Problem(self.loc(node.start_mark), f"YAML tag {shown(tag)} is not allowed in a plan",
                                     "remove the tag", path=path))
        self.reported.add(path)
        return None

    def resolved_number(self, node: Any, path: tuple) -> Any:
        """A scalar YAML resolved as int or float, as PyYAML constructs it; text when PyYAML cannot."""
        tag, text = node.tag, node.value
        try:
            c = yaml.constructor.SafeConstructor()
            value = c.construct_yaml_int(node) if tag.endswith("int") else c.construct_yaml_float(node)
        except ValueError:      # more digits than Python converts (4300)
            self.problems.append(Problem(self.loc(node.start_mark),
                                         f"a number of {len(text)} characters is too long to read",
                                         "write the value with a few digits (a plan's quantities are metres, "
                                         "seconds, percent: small numbers)"))
            self.reported.add(path)
            return None
        except (TypeError, OverflowError, yaml.YAMLError):
            return text
        return self.number(value, text, node, path)

    def number(self, value: int | float, text: str, node: Any, path: tuple) -> int | float | None:
        """A number read from the YAML, or None and a problem when it is not finite."""
        if isinstance(value, float) and not math.isfinite(value):
            self.problems.append(Problem(self.loc(node.start_mark), f"{shown(text)} is not a finite number",
                                         "YAML reads .inf and .nan (and 1e999) as numbers: give a finite one, or "
                                         "quote the text if that is what you meant", path=path))
            self.reported.add(path)
            return None
        return value


def parse_yaml(text: str, file: str, problems: list[Problem]) -> tuple[Any, PositionedYaml]:
    """The plan's values (None when the YAML cannot be read: `problems` says why) and their positions."""
    doc = PositionedYaml(file, problems)
    node = _compose(text, doc, problems)
    if node is None:
        return None, doc
    try:
        data = doc.convert(node, ())
    except _Budget as e:
        problems.append(Problem(file, str(e), "write the plan without anchors and aliases"))
        return None, doc
    except RecursionError:
        problems.append(Problem(file, "the YAML is nested too deeply", _TOO_DEEP_HINT))
        return None, doc
    return data, doc


def _compose(text: str, doc: PositionedYaml, problems: list[Problem]) -> Any:
    """PyYAML's node tree of `text`, or None and a problem (invalid YAML, nested too deeply, empty)."""
    file = doc.file
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = doc.loc(mark) if mark is not None else file
        msg = " ".join(x for x in (e.context, e.problem) if x) or "invalid YAML"
        problems.append(Problem(where, f"invalid YAML: {msg}", _SYNTAX_HINT))
        return None
    except yaml.YAMLError as e:
        problems.append(Problem(file, f"invalid YAML: {clip(str(e), 2 * ECHO_CHARS)}", _SYNTAX_HINT))
        return None
    except RecursionError:
        problems.append(Problem(file, "the YAML is nested too deeply", _TOO_DEEP_HINT))
        return None
    if node is None:
        problems.append(Problem(file, "the plan is empty", "start from `wiris mission schema` or examples/"))
    return node
