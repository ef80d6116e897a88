"""Sphinx configuration of gaitcli's documentation: ``python -m sphinx -W -b html docs docs/_build``.

numpydoc reads the API's docstrings, myst-parser the repository's Markdown (README.md's sections and the design
notes in docs/, included rather than copied), sphinx-click each command's options from click itself.
``tests/test_docs.py`` builds it with warnings as errors.
"""

project = "gaitcli"
author = "the gaitcli engineers"
copyright = "2026, " + author  # noqa: A001  (Sphinx's name)
extensions = ["sphinx.ext.autodoc", "numpydoc", "myst_parser", "sphinx_click"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "examples/*/README.md"]
html_theme = "alabaster"
html_static_path: list[str] = []
# the API's types are documented by their names; a cross-reference to a private module would only warn
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
autodoc_typehints = "none"
autodoc_member_order = "bysource"
myst_heading_anchors = 3
