"""Run one command, then append its wall time, CPU time and peak memory to a log.

    python benchmarks/timestep.py LOG COMMAND [ARGS...]

``benchmarks/demo.py`` passes it as ``make demo RUN=...`` so that each step of the demo is
timed where the Makefile runs it (also when steps run side by side). The command's output
passes through; the exit code is the command's.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time


def main() -> int:
    log, cmd = sys.argv[1], sys.argv[2:]
    t0 = time.time()
    proc = subprocess.Popen(cmd)
    _, status, usage = os.wait4(proc.pid, 0)   # this step's own CPU and peak memory
    t1 = time.time()
    code = os.waitstatus_to_exitcode(status)
    step = " ".join(os.path.basename(c) if i == 0 else c for i, c in enumerate(cmd))
    with open(log, "a") as f:
        f.write(json.dumps({"step": step, "start": t0, "end": t1,
                            "cpu": usage.ru_utime + usage.ru_stime,
                            "peak_mib": usage.ru_maxrss / 1024, "code": code}) + "\n")
    return code


if __name__ == "__main__":
    sys.exit(main())
