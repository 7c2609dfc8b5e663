"""``python -m camjax``: the ``camjax`` command."""

from .cli import command

command()
