"""Write docs/checks.md from the registry of checks (ballimpact.checks.CHECKS).

    python docs/gen_checks.py           # write docs/checks.md
    python docs/gen_checks.py --check   # exit 1 when docs/checks.md differs from the registry
"""

import sys
from pathlib import Path

from ballimpact.checks import checks_markdown

TARGET = Path(__file__).resolve().parent / "checks.md"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    text = checks_markdown() + "\n"
    if "--check" in argv:
        current = TARGET.read_text(encoding="utf-8") if TARGET.exists() else ""
        if current != text:
            print(f"{TARGET} differs from ballimpact.checks.CHECKS: run python docs/gen_checks.py", file=sys.stderr)
            return 1
        return 0
    TARGET.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
