"""Write docs/api.md, SimMeR's public API, from the docstrings of its public modules.

    python scripts/api_docs.py            # write docs/api.md
    python scripts/api_docs.py --check    # exit 1 if docs/api.md is out of date

(with the .venv's python, or once ``source .venv/bin/activate``: it imports simmer).

The public modules are ``simmer._api.PUBLIC``; a module's public names are its ``__all__``.
Each name is documented once, in the public module it is defined in (``simmer.Pose`` points to
``simmer.pose.Pose``); a class shows its own public methods and properties, an enum its
members. ``tests/repository/test_api.py`` runs :func:`render` and fails if the file differs.
"""

from __future__ import annotations

import argparse
import ast
import enum
import importlib
import inspect
import sys
from pathlib import Path
from typing import Any, ForwardRef

from simmer._api import FROM_INTERNAL, INTERNAL, PUBLIC

REPO = Path(__file__).resolve().parent.parent
API_MD = REPO / "docs" / "api.md"
COMMAND = "python scripts/api_docs.py"


def module_source(name: str) -> ast.Module:
    """The parsed source of the module ``name``."""
    module = importlib.import_module(name)
    return ast.parse(inspect.getsource(module))


def assigned(module: str, name: str) -> tuple[str, str | None] | None:
    """Where the value ``module.name`` is assigned (following ``from X import name``, at any
    depth of ``module``'s source: the facade's are under ``TYPE_CHECKING``) and the string
    written under it (an attribute docstring); None if no source says."""
    tree = module_source(module)
    body = tree.body
    for node, after in zip(body, [*body[1:], None], strict=True):
        targets = (
            node.targets
            if isinstance(node, ast.Assign)
            else [node.target]
            if isinstance(node, ast.AnnAssign)
            else []
        )
        if any(isinstance(t, ast.Name) and t.id == name for t in targets):
            doc = None
            if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant):
                doc = after.value.value if isinstance(after.value.value, str) else None
            return module, inspect.cleandoc(doc) if doc else None
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.ImportFrom)
            and node.module
            and node.level == 0
            and any((alias.asname or alias.name) == name for alias in node.names)
        ):
            return assigned(node.module, name)
    return None


def defined_in(module: str, name: str) -> str:
    """The module that defines ``module.name``: a class's or function's own, else where the
    value is assigned."""
    value = getattr(importlib.import_module(module), name)
    if inspect.isclass(value) or inspect.isroutine(value):
        return str(value.__module__)
    found = assigned(module, name)
    return found[0] if found else "?"


def docstring(module: str, name: str) -> str | None:
    """What ``module.name`` says of itself: a class's or function's docstring (its own, not
    a base class's), or the attribute docstring under the value's assignment."""
    value = getattr(importlib.import_module(module), name)
    if inspect.isclass(value) or inspect.isroutine(value):
        doc = value.__doc__
        return inspect.cleandoc(doc) if doc else None
    found = assigned(module, name)
    return found[1] if found else None


def within(module: str, package: str) -> bool:
    """Whether ``module`` is ``package`` or inside it."""
    return module == package or module.startswith(package + ".")


def home(module: str, name: str) -> str:
    """The public module whose section documents ``module.name``: the one it is defined in
    (the innermost), or ``module`` itself for a name taken from an internal module."""
    where = defined_in(module, name)
    homes = [public for public in PUBLIC if within(where, public) and public != "simmer"]
    return max(homes, key=len) if homes else module


def anchor(module: str, name: str) -> str:
    """The Markdown anchor of a name's heading (GitHub's: lower case, no dots)."""
    return f"{module}{name}".lower().replace(".", "")


class _Written(str):
    """An annotation as the source writes it (shown without quotes)."""

    def __repr__(self) -> str:
        return str(self)


def _written(annotation: Any) -> Any:
    """An annotation kept as text (``from __future__ import annotations``; a named tuple's
    are forward references) shown as the source writes it; any other as it is."""
    if isinstance(annotation, ForwardRef):
        return _Written(annotation.__forward_arg__)
    return _Written(annotation) if isinstance(annotation, str) else annotation


def signature(value: Any, *, method: bool = False) -> str:
    """``(arguments) -> result`` as the source writes them (a method's without ``self`` or
    ``cls``); "" where there is none to show (a protocol's)."""
    try:
        sig = inspect.signature(value)
    except (TypeError, ValueError):
        return ""
    params = list(sig.parameters.values())
    if method and params and params[0].name in ("self", "cls"):
        params = params[1:]
    params = [p.replace(annotation=_written(p.annotation)) for p in params]
    shown = str(sig.replace(parameters=params, return_annotation=_written(sig.return_annotation)))
    return "" if shown == "(*args, **kwargs)" else shown


def members(cls: type) -> list[str]:
    """A class's own public methods and properties, an enum's members and a settings model's
    fields (its own: a base model's are under the base), as Markdown items."""
    lines = []
    if _is_model(cls):
        inherited = {name for base in cls.__bases__ for name in getattr(base, "model_fields", {})}
        for name, field in cls.model_fields.items():  # type: ignore[attr-defined]
            if name not in inherited or name in vars(cls).get("__annotations__", {}):
                default = "" if field.is_required() else f" = {field.default!r}"
                said = f": {_flat(field.description)}" if field.description else ""
                lines.append(f"- `{name}{default}`{said}")
    if issubclass(cls, enum.Enum):
        docs = _member_docs(cls)
        for member in cls:
            said = docs.get(member.name)
            lines.append(f"- `{member.name} = {member.value!r}`" + (f": {said}" if said else ""))
    for attr, value in vars(cls).items():
        if attr.startswith("_"):
            continue
        if isinstance(value, property):
            doc, shown = value.__doc__, f"`{attr}` (property)"
        elif isinstance(value, classmethod | staticmethod):
            func = value.__func__
            doc, shown = func.__doc__, f"`{attr}{signature(func, method=True)}`"
        elif inspect.isfunction(value):
            doc, shown = value.__doc__, f"`{attr}{signature(value, method=True)}`"
        else:
            continue
        lines.append(f"- {shown}: {_flat(doc)}" if doc else f"- {shown}")
    return lines


def _member_docs(cls: type) -> dict[str, str]:
    """The attribute docstrings in a class's body, by name."""
    tree = ast.parse(inspect.getsource(cls))
    body = tree.body[0].body if isinstance(tree.body[0], ast.ClassDef) else []
    docs = {}
    for node, after in zip(body, [*body[1:], None], strict=True):
        if (
            isinstance(node, ast.Assign)
            and isinstance(node.targets[0], ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            docs[node.targets[0].id] = _flat(after.value.value)
    return docs


def _flat(doc: str) -> str:
    """A docstring on one line (a list item)."""
    return " ".join(inspect.cleandoc(doc).split())


def _is_model(cls: type) -> bool:
    """Whether ``cls`` is a pydantic model (its signature is its fields': listed instead)."""
    return isinstance(getattr(cls, "model_fields", None), dict)


def kind(value: Any) -> str:
    """What a name is, in a word."""
    if inspect.isclass(value):
        if _is_model(value):
            return "settings model"
        return "enum" if issubclass(value, enum.Enum) else "class"
    if inspect.isroutine(value):
        return "function"
    return "value"


def section(module: str) -> list[str]:
    """The Markdown of one public module: its docstring, then each name it documents."""
    loaded = importlib.import_module(module)
    lines = [f"## `{module}`", "", inspect.cleandoc(loaded.__doc__ or ""), ""]
    for name in loaded.__all__:
        value = getattr(loaded, name)
        where = home(module, name)
        if where != module:
            lines += [f"- `{name}`: see [`{where}.{name}`](#{anchor(where, name)})", ""]
            continue
        shown = f"{name}{signature(value)}" if kind(value) in ("class", "function") else name
        lines += [f"### `{module}.{name}`", "", f"{kind(value)} `{shown}`", ""]
        lines += [docstring(module, name) or "", ""]
        if inspect.isclass(value):
            listed = members(value)
            if listed:
                lines += [*listed, ""]
    return lines


def render() -> str:
    """docs/api.md's text."""
    internal = ", ".join(f"`{name}`" for name in INTERNAL)
    taken = "; ".join(
        f"`{module}`: " + ", ".join(f"`{name}`" for name in names)
        for module, names in FROM_INTERNAL.items()
    )
    lines = [
        "# SimMeR's public API",
        "",
        f"<!-- Generated from the docstrings by `{COMMAND}`: edit the docstrings, then run it. -->",
        "",
        "These modules are SimMeR's public API: what a control program, a device kind of your "
        "own, a sweep or a notebook imports. Each lists its public names in `__all__`, and "
        "`tests/repository/test_api.py` pins them: a change to one is a change to the API.",
        "",
        *[f"- [`{module}`](#{anchor(module, '')})" for module in PUBLIC],
        "",
        "Every other module is internal and may change in any release, as may the modules "
        "inside a public package (`simmer.devices.base`, `simmer.sweep.runs`): import from the "
        f"package. The internal ones (`simmer._api.INTERNAL`): {internal}.",
        "",
        f"A few public names come from an internal module on purpose: {taken}.",
        "",
    ]
    for module in PUBLIC:
        lines += section(module)
    text = "\n".join(lines)
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text.rstrip("\n") + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only say if docs/api.md is stale")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        if API_MD.read_text(encoding="utf-8") != text:
            print(f"docs/api.md is out of date: run `{COMMAND}`", file=sys.stderr)
            return 1
        return 0
    API_MD.write_text(text, encoding="utf-8")
    print(f"wrote {API_MD.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
