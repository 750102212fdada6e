"""Create the ASAM checker's environment (``.venv-qc``) if missing; idempotent.

Run by ``./dev setup`` as ``python -m flyover.opendrive.qc_setup [VENV_PATH]``:
``python -m venv .venv-qc && .venv-qc/bin/python -m pip install
'asam-qc-opendrive>=1.0,<2'`` unless ``.venv-qc`` already imports
``qc_opendrive``. The checker pins ``numpy<2``, hence its own environment.
"""

from __future__ import annotations

import sys

from flyover.opendrive.qc import setup_qc_venv

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    setup_qc_venv(argv[0] if argv else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
