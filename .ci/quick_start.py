"""Print the README's two quick-start commands, one per line, exactly as written (for ``.ci/run``)."""

import re
import sys
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"
section = README.read_text().split("## Quick start", 1)[1].split("\n## ", 1)[0]
commands = re.findall(r"```bash\n(.*?)\n```", section, flags=re.DOTALL)
if len(commands) != 2 or any("\n" in command for command in commands):
    sys.exit(f"the README's quick start should have exactly two one-line commands, found {commands!r}")
print("\n".join(commands))
