"""MkDocs hooks of the documentation site: its figures made before the pages are read, and the API reference checked after the build.

* ``on_pre_build``: runs ``docs/gen_figures.py`` when ``docs/generated/`` is missing or
  older than what it is drawn from (the library, the script, the demo session): a fresh
  clone gets its figures from ``make docs`` alone.
* ``on_post_build``: every public function and class of every module of ``ballimpact``
  has its entry in the built API reference; a missing one is a warning, which fails the
  strict build.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import logging
import runpy
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
GENERATED = REPO / "docs" / "generated"
STAMP = GENERATED / ".inputs-sha256"
log = logging.getLogger("mkdocs.hooks.ballimpact")


def _inputs_digest() -> str:
    """sha256 over the files the figures are drawn from."""
    files = sorted((REPO / "src" / "ballimpact").rglob("*.py")) + [REPO / "docs" / "gen_figures.py"]
    files += sorted(p for p in (REPO / "raw" / "demo-2004").rglob("*") if p.is_file())
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(REPO).as_posix().encode())
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


def on_pre_build(config, **kwargs) -> None:
    digest = _inputs_digest()
    if STAMP.is_file() and STAMP.read_text(encoding="utf-8").strip() == digest:
        return
    log.info("making the figures of the site (docs/gen_figures.py)")
    gen = runpy.run_path(str(REPO / "docs" / "gen_figures.py"), run_name="gen_figures")
    gen["main"](["--out", str(GENERATED)])
    STAMP.write_text(digest + "\n", encoding="utf-8")


def public_names(module_name: str) -> list[str]:
    """Functions and classes a module defines whose names do not start with ``_``."""
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", None) or dir(module)
    return sorted(
        name for name in names
        if not name.startswith("_")
        and (inspect.isfunction(getattr(module, name, None)) or inspect.isclass(getattr(module, name, None)))
        and getattr(getattr(module, name), "__module__", None) == module_name
    )


def public_modules() -> list[str]:
    """Every public module of ``ballimpact`` as its path under the package without ``.py`` (``signal/contact``);
    a subpackage's ``__init__`` as the subpackage (``signal``). Its API page is ``docs/api/<path>.md``
    (``docs/api/signal/index.md`` for a subpackage)."""
    package = REPO / "src" / "ballimpact"
    out = []
    for source in sorted(package.rglob("*.py")):
        parts = source.relative_to(package).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts and not any(p.startswith("_") for p in parts):
            out.append("/".join(parts))
    return out


def api_page(module: str) -> str:
    """The API page of a module of :func:`public_modules`, relative to ``docs/api/``."""
    return f"{module}/index.md" if (REPO / "src" / "ballimpact" / module / "__init__.py").is_file() else f"{module}.md"


def on_post_build(config, **kwargs) -> None:
    site = Path(config["site_dir"])
    for module in public_modules():
        module_name = "ballimpact." + module.replace("/", ".")
        page = site / "api" / module / "index.html"
        if not page.is_file():
            log.warning("API reference: no page for %s (docs/api/%s)", module_name, api_page(module))
            continue
        html = page.read_text(encoding="utf-8")
        missing = [name for name in public_names(module_name) if f'id="{module_name}.{name}"' not in html]
        if missing:
            log.warning("API reference: %s lacks %s", module_name, ", ".join(missing))
