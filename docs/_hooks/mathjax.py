"""mkdocs hook: serve MathJax from the site itself, so formulas render offline (no CDN).

MathJax 3 comes from the ``django-static-mathjax`` package of the ``docs`` extra (a copy of the MathJax
release, no Django needed); its single-file SVG build ``tex-svg.js`` needs no font files, and its licence
(Apache-2.0) is published beside it.
"""

from __future__ import annotations

from importlib import resources

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

#: Where the script lands in the site (``extra_javascript`` of mkdocs.yml names it).
TARGET = "javascripts/mathjax"
SOURCES = {"tex-svg.js": ("es5", "tex-svg.js"), "LICENSE": ("LICENSE",)}


def on_files(files: Files, config) -> Files:  # noqa: ANN001 - mkdocs config object
    try:
        root = resources.files("mathjax").joinpath("static", "mathjax")
    except ModuleNotFoundError:
        raise PluginError("MathJax is missing: install the docs extra (`make install`, or "
                          'pip install -e ".[docs]"), which brings it from the django-static-mathjax package') from None
    for name, parts in SOURCES.items():
        source = root.joinpath(*parts)
        if not source.is_file():
            raise PluginError(f"MathJax file {source} is missing; reinstall django-static-mathjax")
        files.append(File.generated(config, f"{TARGET}/{name}", abs_src_path=str(source)))
    return files
