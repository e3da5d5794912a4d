"""The `mdm-montecarlo` command line: its subcommands (run, reproduce, compare, sweep, plan)
and the files they leave beside their tables."""
