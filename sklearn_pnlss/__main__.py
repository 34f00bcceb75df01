"""``python -m sklearn_pnlss``: the Bouc-Wen study (see ``--help``)."""
import sys

from .app.cli import main

if __name__ == "__main__":
    sys.exit(main())
