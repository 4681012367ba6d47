"""Griffe extension for the API pages: the docstrings' Sphinx roles become cross-references, their seed numbers
the papers' authors and years.

The docstrings write ``:func:`design_gains```, ``:class:`~switchobs.sensors.TimeStamper```,
``:meth:`GeneratedObserver.unranged``` and so on (numpydoc style, readable in ``help()``).  mkdocstrings
renders Markdown, where a role would show as raw text.  When the package is loaded, each role is resolved
in the scope of the object whose docstring holds it (its members, its module's names and imports, then the
enclosing scopes) to the object it names, and rewritten as an autorefs link ``[`text`][identifier]`` to
the place the API pages render that object: the public package that exports it (the lowest layer when
several do, e.g. ``switchobs.model.ParameterBox`` rather than its re-export from ``switchobs.certify``), or
a member of such an object.  A role naming something the pages do not render (a private module, a private
member, a name outside switchobs) stays as code, without the role.  The docstrings cite the papers by their
seed number (``seed 000 eq. (13)``, the files of the specification); the pages cite them by author and year
(``Hoang et al. 2014 eq. (13)``, ``switchobs._papers.cite``), equation numbers kept.  The source is not changed.

Used by mkdocs.yml (``plugins: mkdocstrings: handlers: python: options: extensions``).
"""

from __future__ import annotations

import re
from typing import Any

from griffe import Alias, Extension, Module, Object

from switchobs._papers import cite

#: A Sphinx role: ``:kind:`target``` or ``:kind:`text <target>```.
ROLE = re.compile(r":(?:py:)?(?P<kind>func|meth|class|data|attr|mod|exc|obj|const):`(?P<body>[^`]+)`")


class SphinxRoles(Extension):
    """Rewrites the Sphinx roles of every docstring of the loaded package as autorefs cross-references."""

    def on_package(self, *, pkg: Module, **kwargs: Any) -> None:
        if pkg.name != "switchobs":
            return
        public = _public_paths(pkg)
        for obj in _objects(pkg):
            if obj.docstring is not None:
                text = ROLE.sub(lambda m, o=obj: _link(m, o, pkg, public), obj.docstring.value)
                obj.docstring.value = cite(text)


def _objects(obj: Object):
    """Every object of the package that is defined there (aliases are the objects they point to)."""
    yield obj
    for member in obj.members.values():
        if not isinstance(member, Alias):
            yield from _objects(member)


def _layers(pkg: Module) -> list[str]:
    """The public sub-packages, lowest floor first (``switchobs._layers.FLOORS``), then the exceptions."""
    from switchobs._layers import FLOORS

    names = [name for floor in FLOORS for name in floor if name != "cli"] + ["exceptions"]
    return [name for name in names if name in pkg.members]


def _public_paths(pkg: Module) -> dict[str, str]:
    """Where each object the API pages render is shown: its defining path -> the public identifier."""
    out: dict[str, str] = {}
    for name in _layers(pkg):
        layer = pkg.members[name]
        out.setdefault(layer.path, layer.path)
        for export in layer.exports or ():
            member = layer.members.get(str(export))
            if member is None:
                continue
            try:
                target = member.final_target if isinstance(member, Alias) else member
            except Exception:  # an alias griffe cannot follow: not rendered as an object of switchobs
                continue
            out.setdefault(target.path, f"{layer.path}.{export}")
    return out


def _resolve(obj: Object, name: str, pkg: Module) -> Object | None:
    """The object ``name`` denotes in the docstring of ``obj``: absolute (``switchobs.x.y``) or relative."""
    head, _, rest = name.lstrip(".").partition(".")
    found: Object | None = None
    if head == "switchobs":
        found = pkg
        parts = rest.split(".") if rest else []
    else:
        found = obj.members.get(head)
        if found is None:
            try:  # the object's scope: its members, then its parents' members and imports
                found = pkg.modules_collection.get_member(obj.resolve(head))
            except Exception:  # not in scope: a public name of switchobs if only one has it, else no link
                found = _unique_public(head, pkg)
        parts = rest.split(".") if rest else []
    for part in parts:
        if found is None:
            return None
        try:
            target = found.final_target if isinstance(found, Alias) else found
            found = target.all_members.get(part) if target.is_class else target.members.get(part)
        except Exception:
            return None
    try:
        return found.final_target if isinstance(found, Alias) else found
    except Exception:
        return None


def _unique_public(name: str, pkg: Module) -> Object | None:
    """The object that one public package of switchobs exports as ``name`` (several: ambiguous, None)."""
    found = {}
    for layer in _layers(pkg):
        member = pkg.members[layer].members.get(name)
        if member is not None and name in {str(e) for e in pkg.members[layer].exports or ()}:
            try:
                target = member.final_target if isinstance(member, Alias) else member
            except Exception:
                continue
            found[target.path] = target
    return next(iter(found.values())) if len(found) == 1 else None


def _identifier(target: Object, public: dict[str, str]) -> str | None:
    """The identifier the pages render ``target`` under, or None."""
    if target.path in public:
        return public[target.path]
    parent = target.parent
    if parent is None or not parent.is_class or target.name.startswith("_"):
        return None
    owner = _identifier(parent, public)
    return None if owner is None else f"{owner}.{target.name}"


def _link(match: re.Match[str], obj: Object, pkg: Module, public: dict[str, str]) -> str:
    body = match.group("body").strip()
    explicit = re.fullmatch(r"(?P<text>.+?)\s*<(?P<target>[^>]+)>", body)
    target_name = explicit.group("target") if explicit else body
    short = target_name.startswith("~")
    target_name = target_name.lstrip("~")
    text = explicit.group("text") if explicit else (target_name.rsplit(".", 1)[-1] if short else target_name)
    found = _resolve(obj, target_name, pkg)
    identifier = None if found is None else _identifier(found, public)
    return f"`{text}`" if identifier is None else f"[`{text}`][{identifier}]"
