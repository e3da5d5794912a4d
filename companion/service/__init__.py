"""`companion service`: the systemd unit that starts a vehicle's companion at boot, and the
per-boot mission rule its `companion run` follows."""
