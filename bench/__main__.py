"""``python -m bench [SUITE [ARGS ...]]``: run one suite (``--help`` after its name for its options), ``speed``
for the speed suites in turn (what ``make bench`` runs), or nothing to list the suites."""
from __future__ import annotations

import importlib
import sys

from bench import SPEED, SUITES


def run(name: str, argv: list[str]) -> int:
    module, _ = SUITES[name]
    sys.argv = [f"python -m bench {name}", *argv]      # what bench.stamp records as the command
    return int(importlib.import_module(f"bench.{module}").main(argv) or 0)


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help", "list"):
        width = max(map(len, SUITES))
        print("usage: python -m bench SUITE [ARGS ...]   (python -m bench SUITE --help for its options)\n")
        print("\n".join(f"  {n:<{width}}  {what}" for n, (_, what) in SUITES.items()))
        print(f"  {'speed':<{width}}  " + ", then ".join(" ".join([n, *a]) for n, a in SPEED) + " (make bench)")
        return 0
    name, rest = argv[0], argv[1:]
    if name == "speed":
        return max(run(n, [*a, *rest]) for n, a in SPEED)
    if name not in SUITES:
        import difflib
        near = difflib.get_close_matches(name, SUITES, n=1)
        hint = f" (did you mean {near[0]}?)" if near else ""
        print(f"python -m bench: error: no suite {name!r}{hint}; python -m bench lists them", file=sys.stderr)
        return 2
    return run(name, rest)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
