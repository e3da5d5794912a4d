"""Site files: the fence a field team draws (QGroundControl .plan, KML, GeoJSON) into a profile,
and a profile's fence, search area, start points and targets out to those formats.

Nothing is imported here: `companion run` registers the `profile` command's arguments
(cli_args.py) without loading shapely, fastkml and lxml, which only the command itself needs."""
