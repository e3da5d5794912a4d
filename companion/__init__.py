"""Flight-side software: the MDM search core, guidance, MAVLink link layer and mission."""
