"""The Monte-Carlo engines and their orchestration: a block of runs of one profile (the event
engine for MDM and single-sensor searches, the lawnmower, the time-stepped and waypoint swarms),
the dt-stepping reference that checks them, and ``runner`` spreading blocks over local workers
or Dask. They call the kernels below them and know nothing of tables or reports."""
