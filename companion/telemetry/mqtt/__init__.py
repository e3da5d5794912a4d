"""MQTT for the companion: a reconnecting channel, the durable event outbox, state, status, commands.

Nothing here is imported unless a broker is configured (profile ``mqtt:`` or ``--mqtt``).
"""
