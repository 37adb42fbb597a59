"""``shapecond cache info|clear``: the on-disk cache of distance matrices and landmarks."""

from __future__ import annotations

import click

from .. import cache as disk
from ..limits import human_bytes
from .common import emit_json, json_option


@click.group("cache")
def command():
    """Show or empty the cache folder ($SHAPECOND_CACHE or the platform's cache folder)."""


@command.command("info")
@json_option
def info(as_json):
    """Folder, number of entries and their size, by kind."""
    report = disk.info()
    if as_json:
        emit_json(report)
        return
    click.echo(f"folder   {report['folder']}")
    click.echo(f"entries  {report['entries']} ({human_bytes(report['bytes'])})")
    if report["other_files"]:
        click.echo(f"other    {report['other_files']} files that are not cache entries (never removed)")
    for kind, k in sorted(report["kinds"].items()):
        click.echo(f"  {kind:10s} {k['entries']:6d}  {human_bytes(k['bytes'])}")


@command.command("clear")
@json_option
def clear(as_json):
    """Delete every cache entry (results are recomputed when next needed).

    Only the cache's own files are removed: entries recognised by their name and
    content (their key and checksum), the cache's temporary files and its secret;
    any other file in the folder is kept.
    """
    report = disk.clear()
    if as_json:
        emit_json(report)
        return
    click.echo(f"removed {report['removed']} entries ({human_bytes(report['bytes'])}) from {report['folder']}")
    if report["kept"]:
        click.echo(f"kept {report['kept']} files that are not cache entries", err=True)
