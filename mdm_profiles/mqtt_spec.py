"""The optional ``mqtt:`` section of a profile: broker, credentials (never a literal secret), TLS."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class MqttTlsSpec(_Strict):
    """TLS to the broker; paths are PEM files. ``insecure`` skips the host-name check only."""

    ca: str | None = Field(default=None, description="CA certificate that signed the broker's.")
    cert: str | None = Field(default=None, description="Client certificate (mutual TLS).")
    key: str | None = Field(default=None, description="Client private key (mutual TLS).")
    insecure: bool = Field(default=False, description="Do not check the broker's host name.")

    @model_validator(mode="after")
    def _pair(self) -> MqttTlsSpec:
        if (self.cert is None) != (self.key is None):
            raise ValueError("tls.cert and tls.key go together")
        return self


class MqttSpec(_Strict):
    """Where a companion publishes state and events and takes operator commands.

    ``{vehicle}`` in ``username``, ``password_env`` and ``password_file`` is replaced by the
    vehicle index, so each companion can have its own account.
    """

    host: str = Field(min_length=1)
    port: int = Field(default=1883, ge=1, le=65535)
    username: str | None = None
    password_env: str | None = Field(
        default=None, description="Name of the environment variable holding the password."
    )
    password_file: str | None = Field(
        default=None, description="File whose first line is the password."
    )
    tls: MqttTlsSpec | None = None
    state_rate: float = Field(
        default=2.0, gt=0, le=50, description="State messages per wall second."
    )
    topic_prefix: str | None = Field(
        default=None, description="Topics are <prefix>/uav<i>/...; default mdm/<profile name>."
    )
    keepalive: int = Field(default=10, ge=2, le=3600, description="MQTT keepalive, s.")

    @model_validator(mode="before")
    @classmethod
    def _no_literal_secret(cls, data: Any) -> Any:
        if isinstance(data, dict) and "password" in data:
            raise ValueError(
                "a literal password is not allowed in a profile; use password_env "
                "(an environment variable) or password_file"
            )
        return data

    @model_validator(mode="after")
    def _one_secret(self) -> MqttSpec:
        if self.password_env is not None and self.password_file is not None:
            raise ValueError("give password_env or password_file, not both")
        if (self.password_env or self.password_file) and self.username is None:
            raise ValueError("a password needs a username")
        prefix = self.topic_prefix
        if prefix is not None and (
            not prefix or prefix.startswith("/") or prefix.endswith("/") or set(prefix) & set("+#")
        ):
            raise ValueError(f"topic_prefix {prefix!r}: no leading or trailing '/', no + or #")
        return self
