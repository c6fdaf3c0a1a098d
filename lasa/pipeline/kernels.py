"""Record the numerical kernels a run computes with: ``figures/kernels.json``.

``make figures`` runs ``python -m lasa.pipeline.kernels --out <figures>/kernels.json`` before the
notebooks, which inherit its environment: the variables of :data:`lasa.base.kernels.PINNED` as
set, whether each holds its pinned value, and torch's CPU capability. ``make verify`` prints the
file of both runs above its table (:func:`lasa.pipeline.verify.kernels_text`).
"""

from __future__ import annotations

import argparse
import json
import sys

from lasa.base.io import write_text
from lasa.base.kernels import kernel_settings

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """``python -m lasa.pipeline.kernels [--out FILE]``: the settings in effect, as JSON."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--out", help="write the JSON to this file (else print it)")
    args = parser.parse_args(argv)
    text = json.dumps(kernel_settings(), indent=2, sort_keys=True) + "\n"
    if args.out is None:
        sys.stdout.write(text)
    else:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
