"""The README's first-screen commands, one per line: the non-comment lines of its first ```bash
block. `.ci/run` runs them verbatim in a copy of the repository with nothing beside it, and
tests/test_standalone.py checks that they are the two the README promises (install + main job,
install + tests), so the README and CI cannot drift apart."""

import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def commands(text: str) -> list[str]:
    lines = text.splitlines()
    start = lines.index("```bash") + 1
    end = lines.index("```", start)
    return [line.strip() for line in lines[start:end] if line.strip() and not line.strip().startswith("#")]


if __name__ == "__main__":
    cmds = commands(README.read_text(encoding="utf-8"))
    if len(cmds) != 2:
        sys.exit(f"README.md: the first bash block must hold two commands (install + run, install + test), found {len(cmds)}")
    print("\n".join(cmds))
