"""The study of the paper's section IV on top of the engines: the cases and their tolerances,
the paper's published numbers, named variants, measured tables, the report and its figures,
per-run samples, comparisons, sweeps and the team planner."""
