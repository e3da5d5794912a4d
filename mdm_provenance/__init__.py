"""What made a result: the package version, the code's git commit, the interpreter, the
numerical libraries, the CPU, the seed, the command line and the time it took.

Read by every results writer (mdm-montecarlo's reports, samples and sweeps; the fleet's
results.json) and by each command's ``--version``. Imports nothing of the project.
"""

from mdm_provenance.record import (
    Provenance,
    collect,
    cpu_seconds,
    package_version,
    version_text,
)
from mdm_provenance.version_flag import add_version_flag

__all__ = [
    "Provenance",
    "add_version_flag",
    "collect",
    "cpu_seconds",
    "package_version",
    "version_text",
]
