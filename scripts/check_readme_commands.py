"""Run the README's two set-up commands in a clean clone, as a new user would.

    python scripts/check_readme_commands.py [--keep]

Clones the repository's HEAD into a temporary folder that has no ``../shared`` beside it and no
``.venv``, then runs the first two shell commands of the README's first ``bash`` block there,
one after the other (command 1 installs from requirements.lock and plans the demo, command 2
runs the tests). A missing install step, a README that drifted from the code or a test that
needs ../shared without skipping fails here instead of on a new user's machine. CI runs it.
Uncommitted changes are not part of the clone: commit first.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def readme_commands(readme: Path) -> list[str]:
    """The commands of the README's first ```bash block (comment lines dropped)."""
    text = readme.read_text(encoding="utf-8")
    block = re.search(r"```bash\n(.*?)```", text, re.S)
    if block is None:
        raise SystemExit(f"{readme}: no ```bash block")
    commands = [x for x in block.group(1).splitlines() if x.strip() and not x.startswith("#")]
    if len(commands) != 2:
        raise SystemExit(f"{readme}: the first bash block has {len(commands)} commands, not 2")
    return commands


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", action="store_true", help="keep the clone (path printed)")
    args = parser.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="weldplan-readme-"))
    clone = tmp / "weldplan"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    assert not (clone.parent / "shared").exists()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("WELDPLAN_", "VIRTUAL_ENV"))}
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".venv" not in p
    )
    code = 0
    for k, command in enumerate(readme_commands(clone / "README.md"), 1):
        print(f"README command {k}: {command}", flush=True)
        t = time.perf_counter()
        done = subprocess.run(["bash", "-c", f"set -eo pipefail; {command}"], cwd=clone, env=env)
        print(f"README command {k}: exit {done.returncode} in {time.perf_counter() - t:.0f} s")
        if done.returncode != 0:
            code = 1
            break
    if args.keep:
        print(f"clone kept at {clone}")
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    return code


if __name__ == "__main__":
    sys.exit(main())
