"""Monte-Carlo engine: batched missions, the paper's metrics, tables and reports, in rooms by
job, each importing only the rooms listed before it: ``kernels`` (compiled numba loops),
``engines`` (a block of runs of one profile, and ``runner`` spreading blocks over workers),
``study`` (section IV's cases, tables, report, samples, sweeps, the planner) and ``commands``
(the `mdm-montecarlo` command line)."""
