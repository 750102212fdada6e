"""Create the clients' environment (``.venv-clients``) if missing; idempotent.

Run by ``./dev setup`` as ``python -m flyover.clients.setup [VENV_PATH]``. A
stamp file makes a second run return at once.
"""

from __future__ import annotations

import sys

from flyover.clients.tools import setup_clients_venv

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    setup_clients_venv(argv[0] if argv else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
