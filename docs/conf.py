"""Sphinx configuration for tensor_cosdi (``pip install ".[docs]"``, then
``sphinx-build docs docs/_build/html``)."""

project = "tensor_cosdi"
author = "tensor_cosdi developers"
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "myst_parser",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
autosummary_generate = True
# API pages end with the gallery examples that use the object (sphinx-gallery backreferences)
templates_path = ["_templates"]
numpydoc_show_class_members = False
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "backreferences_dir": "gen_modules/backreferences",
    "doc_module": ("tensor_cosdi",),
}
html_theme = "alabaster"
exclude_patterns = ["_build"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
