"""The --mqtt* flags of `companion run` and `companion fleet`, merged over the profile's mqtt:.

No aiomqtt here: parsing flags is not an MQTT code path.
"""

from __future__ import annotations

import argparse
from typing import Any

from pydantic import ValidationError

from mdm_profiles.mqtt_spec import MqttSpec

_FLAGS: dict[str, str] = {
    # dest -> MqttSpec field (host and port come from --mqtt)
    "mqtt_username": "username",
    "mqtt_password_env": "password_env",
    "mqtt_password_file": "password_file",
    "mqtt_state_rate": "state_rate",
    "mqtt_prefix": "topic_prefix",
}
_TLS_FLAGS = {"mqtt_ca": "ca", "mqtt_cert": "cert", "mqtt_key": "key"}


def add_mqtt_arguments(p: argparse.ArgumentParser) -> None:
    """Register the flags; each overrides the profile's ``mqtt:`` section."""
    g = p.add_argument_group("MQTT (default: the profile's mqtt: section, else no MQTT)")
    g.add_argument("--mqtt", metavar="HOST[:PORT]", help="broker (port 1883 if not given)")
    g.add_argument("--mqtt-username", metavar="USER", help="'{vehicle}' -> vehicle index")
    g.add_argument("--mqtt-password-env", metavar="VAR", help="variable holding the password")
    g.add_argument("--mqtt-password-file", metavar="PATH", help="file holding the password")
    g.add_argument("--mqtt-ca", metavar="PEM", help="TLS: CA certificate of the broker")
    g.add_argument("--mqtt-cert", metavar="PEM", help="TLS: client certificate")
    g.add_argument("--mqtt-key", metavar="PEM", help="TLS: client key")
    g.add_argument("--mqtt-insecure", action="store_true", help="TLS: skip the host-name check")
    g.add_argument("--mqtt-state-rate", type=float, metavar="HZ", help="state messages per s")
    g.add_argument("--mqtt-prefix", metavar="PREFIX", help="topic prefix (default mdm/PROFILE)")


def parse_broker(value: str) -> tuple[str, int | None]:
    """``HOST``, ``HOST:PORT`` or ``[IPV6]:PORT`` -> (host, port or None)."""
    if value.startswith("["):
        host, _, rest = value[1:].partition("]")
        if rest and not rest.startswith(":"):
            raise ValueError(f"--mqtt {value!r}: expected [IPV6]:PORT")
        port = rest[1:]
    elif value.count(":") == 1:
        host, _, port = value.partition(":")
    else:
        host, port = value, ""  # a name, or a bare IPv6 address
    if not host:
        raise ValueError(f"--mqtt {value!r}: no host")
    if not port:
        return host, None
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ValueError(f"--mqtt {value!r}: port must be a number 1-65535")
    return host, int(port)


def mqtt_spec(args: argparse.Namespace, profile_spec: MqttSpec | None) -> MqttSpec | None:
    """The profile's spec with the flags applied; None when no broker is configured at all."""
    given = {
        field: getattr(args, dest)
        for dest, field in _FLAGS.items()
        if getattr(args, dest) is not None
    }
    tls = {
        field: getattr(args, dest)
        for dest, field in _TLS_FLAGS.items()
        if getattr(args, dest) is not None
    }
    if args.mqtt_insecure:
        tls["insecure"] = True
    if args.mqtt is None and profile_spec is None:
        if given or tls:
            raise ValueError("--mqtt-* options need --mqtt HOST[:PORT] or an mqtt: section")
        return None
    data: dict[str, Any] = profile_spec.model_dump(exclude_unset=True) if profile_spec else {}
    if args.mqtt is not None:
        host, port = parse_broker(args.mqtt)
        data["host"] = host
        if port is not None:
            data["port"] = port
    data |= given
    if tls:
        data["tls"] = dict(data.get("tls") or {}) | tls
    try:
        return MqttSpec.model_validate(data)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(map(str, e['loc'])) or 'mqtt'}: {e['msg']}" for e in exc.errors()
        )
        raise ValueError(f"MQTT settings: {problems}") from None


def mqtt_argv(args: argparse.Namespace) -> list[str]:
    """The same flags again, for the `companion run` processes of a fleet."""
    argv: list[str] = []
    for dest in ("mqtt", *_FLAGS, *_TLS_FLAGS):
        value = getattr(args, dest)
        if value is not None:
            argv += ["--" + dest.replace("_", "-"), str(value)]
    if args.mqtt_insecure:
        argv.append("--mqtt-insecure")
    return argv
