"""Print the README's quick-start commands, one a line: the lines of the first ```bash block after
the "## Quick start" heading. .ci/run runs them as written, so CI does what a new user reads."""

import sys
from pathlib import Path


def quickstart(readme: str) -> list[str]:
    lines = readme.splitlines()
    start = lines.index("## Quick start")
    fence = next(i for i in range(start, len(lines)) if lines[i].strip() == "```bash")
    end = next(i for i in range(fence + 1, len(lines)) if lines[i].strip() == "```")
    return [line for line in lines[fence + 1:end] if line.strip()]


if __name__ == "__main__":
    print("\n".join(quickstart(Path(sys.argv[1]).read_text(encoding="utf-8"))))
