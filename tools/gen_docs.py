"""Generate the documentation pages that are read off the code.

- ``docs/reference/cli.md``: every sub-command's ``--help``, from the argparse parsers of
  ``openpbr_diffuse.cli.main.build_parser`` (80 columns, no colour);
- the import table of ``docs/design/layering.md`` (between its ``<!-- layering:begin -->`` and
  ``<!-- layering:end -->`` markers): which sub-package imports which, read from every module's
  ``import`` statements (lazy ones inside functions included) with ``ast``;
- the module-size tables of the design pages ``docs/design/surface-engine.md``,
  ``report.md`` and ``graders.md`` (between their ``<!-- module-sizes:begin -->`` and
  ``<!-- module-sizes:end -->`` markers): the lines of each module the page describes and
  the first sentence of its docstring.

Usage::

    python tools/gen_docs.py           # rewrite the generated parts
    python tools/gen_docs.py --check   # exit 1 and name the files that are out of date

``tests/test_docs_site.py`` runs the check.
"""

from __future__ import annotations

import argparse
import ast
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "openpbr_diffuse"
CLI_PAGE = ROOT / "docs" / "reference" / "cli.md"
LAYERING_PAGE = ROOT / "docs" / "design" / "layering.md"
BEGIN, END = "<!-- layering:begin -->", "<!-- layering:end -->"
ENGINE_PAGE = ROOT / "docs" / "design" / "surface-engine.md"
SIZES_BEGIN, SIZES_END = "<!-- module-sizes:begin -->", "<!-- module-sizes:end -->"
#: the surface engine's modules, in the order of the table (the lobe modules after them)
ENGINE_MODULES = (
    "nodes/surface_inputs.py",
    "nodes/_surface_params.py",
    "nodes/_surface_kernels.py",
    "nodes/_surface_passes.py",
    "nodes/_surface_drivers.py",
    "nodes/lobes/__init__.py",
    "nodes/lobes/_common.py",
    "nodes/lobes/_samplers.py",
)


def cli_page() -> str:
    """The CLI reference page: the top-level help, then each sub-command's help."""
    os.environ["COLUMNS"] = "80"  # argparse wraps to the terminal width: fix it
    os.environ["NO_COLOR"] = "1"  # Python >= 3.14 colours help text otherwise
    sys.path.insert(0, str(ROOT))
    from openpbr_diffuse.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = [
        "# Command-line reference",
        "",
        "Generated from the argument parsers by `python tools/gen_docs.py` (a test checks that",
        "this page is up to date). Conventions shared by every command (exit status, errors,",
        "numbers that start with a minus, pipes, Ctrl-C): [Command-line conventions](../guide/command-line.md).",
        "",
        "## `openpbr-diffuse`",
        "",
        "```text",
        parser.format_help().rstrip(),
        "```",
        "",
    ]
    for name, cmd in sub.choices.items():
        out += [f"## `openpbr-diffuse {name}`", "", "```text", cmd.format_help().rstrip(), "```", ""]
    return "\n".join(out)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """Sub-package (``models``, ``nodes``, ...; ``_jit`` etc. for top-level modules) ->
    the sub-packages its modules import."""
    modules = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        if name == "openpbr_diffuse":
            continue  # the package's __init__ re-exports the public names of every sub-package
        own = name.split(".")[1]
        is_package = path.name == "__init__.py"
        deps = graph.setdefault(own, set())
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".")
                    if not is_package:
                        base = base[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets = [f"{mod}.{a.name}" for a in node.names] + [mod]
            else:
                continue
            for t in targets:
                parts = t.split(".")
                if parts[0] == "openpbr_diffuse" and len(parts) > 1:
                    other = parts[1]
                    if other != own and f"openpbr_diffuse.{other}" in modules:
                        deps.add(other)
    return graph


def depths(graph: dict[str, set[str]]) -> dict[str, int]:
    """Layer of each sub-package: 0 for one that imports no other, else 1 + the deepest it
    imports (the graph has no circle: ``tests/test_import_layering.py``)."""
    memo: dict[str, int] = {}

    def depth(p: str) -> int:
        if p not in memo:
            memo[p] = 1 + max((depth(d) for d in graph.get(p, ())), default=-1)
        return memo[p]

    return {p: depth(p) for p in graph}


def layering_table() -> str:
    graph = import_graph()
    layer = depths(graph)
    rows = ["| layer | sub-package | imports from the package |", "|---|---|---|"]
    for pkg in sorted(graph, key=lambda p: (layer[p], p.startswith("_"), p)):
        deps = ", ".join(f"`{d}`" for d in sorted(graph[pkg], key=lambda p: (layer[p], p))) or "—"
        rows.append(f"| {layer[pkg]} | `{pkg}` | {deps} |")
    return "\n".join(rows)


def layering_page(current: str) -> str:
    head, rest = current.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{BEGIN}\n{layering_table()}\n{END}{tail}"


def _engine_modules() -> tuple[str, ...]:
    lobes = sorted(p.relative_to(PACKAGE).as_posix() for p in (PACKAGE / "nodes" / "lobes").glob("[!_]*.py"))
    return (*ENGINE_MODULES, *lobes)


def _package_modules(*folders: str) -> tuple[str, ...]:
    """Every module of the given sub-packages, ``__init__`` first, then by name."""
    out: list[str] = []
    for folder in folders:
        paths = sorted((PACKAGE / folder).glob("*.py"), key=lambda p: (p.name != "__init__.py", p.name))
        out += [p.relative_to(PACKAGE).as_posix() for p in paths]
    return tuple(out)


#: the design pages with a generated module-size table, and the modules each describes
DESIGN_PAGES = {
    ENGINE_PAGE: _engine_modules,
    ROOT / "docs" / "design" / "report.md": lambda: ("result.py", *_package_modules("report", "report/sections")),
    ROOT / "docs" / "design" / "graders.md": lambda: _package_modules("graders", "conformance"),
}


def module_sizes_table(modules: tuple[str, ...] | None = None) -> str:
    """| module | lines | holds | of ``modules`` (default: the surface engine's and its lobes')."""
    rows = ["| module | lines | holds |", "|---|---|---|"]
    for rel in modules or _engine_modules():
        text = (PACKAGE / rel).read_text(encoding="utf-8")
        doc = ast.get_docstring(ast.parse(text)) or ""
        first = " ".join(doc.split("\n\n")[0].split()).split(". ")[0].rstrip(".") + "."
        first = first.replace("|", "\\|")
        rows.append(f"| `{rel}` | {len(text.splitlines())} | {first} |")
    return "\n".join(rows)


def module_sizes_page(current: str, modules: tuple[str, ...] | None = None) -> str:
    head, rest = current.split(SIZES_BEGIN, 1)
    _, tail = rest.split(SIZES_END, 1)
    return f"{head}{SIZES_BEGIN}\n{module_sizes_table(modules)}\n{SIZES_END}{tail}"


def targets() -> dict[Path, str]:
    return {
        CLI_PAGE: cli_page() + "\n",
        LAYERING_PAGE: layering_page(LAYERING_PAGE.read_text(encoding="utf-8")),
        **{
            page: module_sizes_page(page.read_text(encoding="utf-8"), modules())
            for page, modules in DESIGN_PAGES.items()
        },
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare instead of writing; exit 1 if out of date")
    args = ap.parse_args(argv)
    stale = []
    for path, text in targets().items():
        if path.exists() and path.read_text(encoding="utf-8") == text:
            continue
        stale.append(path)
        if not args.check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
    for path in stale:
        print(f"{'out of date' if args.check else 'wrote'}: {path.relative_to(ROOT)}")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    sys.exit(main())
