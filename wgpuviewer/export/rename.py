"""Module-scope names of a composed WGSL module, and their prefixing, so an exported module sits next to a user's
own code without a clash: every function, struct, constant, alias and variable declared at module scope gets the
project's prefix by its case (``depth_at`` -> ``relief_depth_at``, ``TraceResult`` -> ``ReliefTraceResult``,
``MAX_LAYERS`` -> ``RELIEF_MAX_LAYERS``).

May import: nothing of the project (plain text work).
"""

from __future__ import annotations

import re

_DECLARATION = re.compile(r"^\s*(?:@[\w]+(?:\([^)]*\))?\s*)*(?:fn|struct|const|override|alias|var(?:<[^>]*>)?)\s+(\w+)")
_STRUCT_OPEN = re.compile(r"^\s*struct\s+\w+")
_MEMBER = re.compile(r"^(\s*(?:@[\w]+(?:\([^)]*\))?\s*)*\w+\s*:)(.*)$")


def _code(line: str) -> str:
    """A line without its ``//`` comment (brace counting must not see the braces of prose)."""
    return line.split("//", 1)[0]


def module_names(code: str) -> list[str]:
    """The names declared at module scope (brace depth 0), in order."""
    names, depth = [], 0
    for line in code.splitlines():
        text = _code(line)
        if depth == 0:
            match = _DECLARATION.match(text)
            if match:
                names.append(match.group(1))
        depth += text.count("{") - text.count("}")
    return names


def prefixed(name: str, taken: set[str] = frozenset()) -> str:
    """``name`` with the prefix its case asks for; a result in ``taken`` (the module's own API names) gets
    ``technique_`` in between (the technique's ``trace`` is ``relief_technique_trace``: ``relief_trace`` is the
    API around it)."""
    if name.isupper() or (name.upper() == name and "_" in name):
        prefix, inner = "RELIEF_", "TECHNIQUE_"
    elif name[0].isupper():
        prefix, inner = "Relief", "Technique"
    else:
        prefix, inner = "relief_", "technique_"
    out = prefix + name
    return prefix + inner + name if out in taken else out


def rename(code: str, mapping: dict[str, str]) -> str:
    """``code`` with every identifier in ``mapping`` replaced, except where it is a member (after a '.', and the
    member names a struct declares: their types are renamed) and in comments."""
    if not mapping:
        return code
    word = re.compile(r"(?<![\w.])(" + "|".join(sorted(map(re.escape, mapping), key=len, reverse=True)) + r")\b")

    def sub(text: str) -> str:
        return word.sub(lambda m: mapping[m.group(1)], text)

    out, depth, in_struct = [], 0, False
    for line in code.splitlines():
        text = _code(line)
        comment = line[len(text):]  # prose keeps the names it was written with
        if depth == 0 and _STRUCT_OPEN.match(text):
            in_struct = True
        member = _MEMBER.match(text) if in_struct and depth == 1 else None
        out.append((member.group(1) + sub(member.group(2)) if member else sub(text)) + comment)
        depth += text.count("{") - text.count("}")
        if depth == 0:
            in_struct = False
    return "\n".join(out) + "\n"
