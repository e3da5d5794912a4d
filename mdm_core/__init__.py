"""The pure core below every other package: the search policy (``search``), the world model
(``world``: area, targets, sensors, scenario), the tau-lag vehicle dynamics (``dynamics``) and
mission metrics (``metrics``).

No sockets, clocks or files. Imports run one way: ``mdm_profiles`` <- ``mdm_core`` <-
{``companion``, ``sim_vehicle_stub``, ``mdm_montecarlo``} (tests/test_import_direction.py).
"""
