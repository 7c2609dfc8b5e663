"""MkDocs hook: serve the repository's figures and notebooks as site files.

The results pages in ``docs/`` link their figures as ``../results/<study>/<name>.png``, the
path that works on a source checkout.  This hook adds every figure under ``results/`` with
that source path (``../results/...``) and a destination inside the site (``results/...``),
so MkDocs resolves and checks those links like any other (a missing figure fails the strict
build), and rewrites them to the copy in the site.  It also adds the jupytext notebooks
``notebooks/*.py`` as ``notebooks/<name>.py``, which mkdocs-jupyter then renders.  Nothing
is copied into ``docs/``, so there is one file for each figure and notebook.
"""

from __future__ import annotations

from pathlib import Path

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File, InclusionLevel

FIGURE_SUFFIXES = {".png", ".svg", ".jpg"}


@event_priority(100)  # before mkdocs-jupyter turns notebook files into pages
def on_files(files, config):
    root = Path(config.config_file_path).parent
    # INCLUDED up front: MkDocs' default exclusions (hidden paths, ".*") would match "..".
    site = {"dest_dir": config.site_dir, "use_directory_urls": config.use_directory_urls,
            "inclusion": InclusionLevel.INCLUDED}
    for path in sorted((root / "results").rglob("*")):
        if path.suffix in FIGURE_SUFFIXES and "tmp" not in path.relative_to(root).parts:
            relative = path.relative_to(root).as_posix()
            files.append(File(f"../{relative}", config.docs_dir, dest_uri=relative, **site))
    for path in sorted((root / "notebooks").glob("*.py")):
        files.append(File(f"notebooks/{path.name}", str(root), **site))
    return files
