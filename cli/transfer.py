"""``omninoise transfer``: print or save a transfer-function preset as an editable ramp."""
from __future__ import annotations

import argparse

from omninoise.backend.transfer import PRESETS

from . import listing
from .common import add_command

__all__ = ["add_parser", "run"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The subcommand's parser, added to ``sub`` (the top parser's subparsers)."""
    t = add_command(sub, "transfer", "print or save a transfer-function preset as an editable ramp",
                    "Transfer functions map noise values to colour, density and temperature, as Blender's Color Ramp "
                    "does. Save a preset as a ramp .json, edit it, and pass it to --transfer or a job file.",
                    """omninoise transfer --list
omninoise transfer fire -o my_ramp.json""")
    t.add_argument("preset", nargs="?", choices=tuple(PRESETS), help="the preset to print or save")
    t.add_argument("--list", action="store_true", help="list the presets")
    t.add_argument("-o", "--out", help="write the ramp here (default: print it)")
    return t


def run(a: argparse.Namespace) -> int:
    import json

    from omninoise.backend.bake import output_type
    from omninoise.backend.errors import SettingError
    from omninoise.backend.transfer import preset

    if a.list and a.preset:
        raise SettingError("--list", "lists the presets; leave out the preset name, or --list to print the preset")
    if a.out and not a.preset:
        raise SettingError("-o", f"saves a preset: give its name ({', '.join(PRESETS)})")
    if a.out:
        output_type(a.out, (".json",), "a ramp", "-o")
    if a.list or not a.preset:
        from omninoise.backend.transfer import PRESET_NOTES
        print(listing.presets_text({name: PRESET_NOTES[name] for name in PRESETS}))
        return 0
    text = json.dumps(preset(a.preset).to_dict(), indent=2)
    if not a.out:
        print(text)
        return 0
    from omninoise.export.atomic import atomic_path

    with atomic_path(a.out) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    return 0
