"""Broker connection settings resolved from a profile's ``mqtt:`` section: secrets read here."""

from __future__ import annotations

import os
import ssl
from dataclasses import dataclass, field
from pathlib import Path

import aiomqtt

from mdm_profiles.mqtt_spec import MqttSpec, MqttTlsSpec


@dataclass(frozen=True)
class MqttSettings:
    """Where and as whom to connect; the password never appears in ``repr``."""

    host: str
    port: int = 1883
    username: str | None = None
    password: str | None = field(default=None, repr=False)
    tls: MqttTlsSpec | None = None
    keepalive: int = 10

    def client(
        self, *, identifier: str, will: aiomqtt.Will | None = None, clean_session: bool = True
    ) -> aiomqtt.Client:
        """A new (not yet connected) aiomqtt client; call inside the running event loop."""
        tls = self.tls
        return aiomqtt.Client(
            self.host,
            self.port,
            username=self.username,
            password=self.password,
            identifier=identifier,
            will=will,
            clean_session=clean_session,
            keepalive=self.keepalive,
            timeout=10.0,
            tls_params=None
            if tls is None
            else aiomqtt.TLSParameters(
                ca_certs=tls.ca, certfile=tls.cert, keyfile=tls.key, cert_reqs=ssl.CERT_REQUIRED
            ),
            tls_insecure=None if tls is None else tls.insecure,
        )


def settings_for(spec: MqttSpec, vehicle: int) -> MqttSettings:
    """Resolve ``{vehicle}`` templates, read the password from its variable or file, check TLS files."""

    def fill(template: str) -> str:
        return template.replace("{vehicle}", str(vehicle))

    password: str | None = None
    if spec.password_env is not None:
        name = fill(spec.password_env)
        password = os.environ.get(name)
        if not password:
            raise ValueError(f"mqtt.password_env: environment variable {name} is not set")
    elif spec.password_file is not None:
        path = Path(fill(spec.password_file))
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            raise ValueError(f"mqtt.password_file {path}: {exc.strerror}") from None
        password = lines[0].strip() if lines else ""
        if not password:
            raise ValueError(f"mqtt.password_file {path}: the first line is empty")
    if spec.tls is not None:
        for what in ("ca", "cert", "key"):
            name = getattr(spec.tls, what)
            if name is not None and not Path(name).is_file():
                raise ValueError(f"mqtt.tls.{what} {name}: no such file")
    return MqttSettings(
        host=spec.host,
        port=spec.port,
        username=None if spec.username is None else fill(spec.username),
        password=password,
        tls=spec.tls,
        keepalive=spec.keepalive,
    )
