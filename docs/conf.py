"""Sphinx configuration of the ntc-design documentation (``python -m sphinx -W -b html docs
docs/_build/html``): the user guide, the API reference from the numpydoc docstrings, the CLI
reference from the commands themselves and a gallery of executed examples."""

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
HERE = Path(__file__).resolve().parent
os.chdir(HERE.parent)  # the gallery's examples read examples/ from the checkout

project = "ntc-design"
author = "the ntc-design developers"
copyright = "2026, the ntc-design developers"  # noqa: A001 - Sphinx's name

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
]
autosummary_generate = True
autodoc_typehints = "none"  # the numpydoc sections say it, once
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_heading_anchors = 3
exclude_patterns = ["_build", "_generated", "gallery/README.rst"]  # _generated: included
html_theme = "pydata_sphinx_theme"
html_title = "ntc-design"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path = ["_static"]
html_css_files = ["custom.css"]

sphinx_gallery_conf = {
    "examples_dirs": str(HERE / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
}
doctest_global_setup = f"import os; os.chdir({str(HERE.parent)!r})"


def _cli_reference(app) -> None:
    """docs/cli_commands.rst from ``ntc COMMAND --help`` itself, so that it never drifts."""
    from typer.testing import CliRunner

    from ntc_design.cli.program import app as ntc

    runner = CliRunner()
    names = [c.name or c.callback.__name__ for c in ntc.registered_commands]
    out = []
    for name in ["", *names]:
        res = runner.invoke(ntc, [*([name] if name else []), "--help"], prog_name="ntc")
        title = f"ntc {name}".strip()
        out += [title, "-" * len(title), "", ".. code-block:: text", ""]
        out += ["   " + line.rstrip() for line in res.output.splitlines()] + [""]
    (HERE / "cli_commands.rst").write_text("\n".join(out), encoding="utf-8")


def setup(app):
    app.connect("builder-inited", _cli_reference)
