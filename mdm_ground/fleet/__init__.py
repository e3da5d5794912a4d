"""`companion fleet`: the emulator and N companion processes on this machine, with a summary."""
