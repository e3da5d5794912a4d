"""Connection URLs: accepted spellings and clear errors."""

from __future__ import annotations

import pytest

from companion.link.address import parse_address


def test_udpin_and_mavsdk_spelling() -> None:
    a = parse_address("udpin://0.0.0.0:14541")
    assert (a.scheme, a.host, a.port) == ("udpin", "0.0.0.0", 14541)
    assert a.mavsdk_url() == "udpin://0.0.0.0:14541"
    assert parse_address("tcp:127.0.0.1:5760").mavsdk_url() == "tcpout://127.0.0.1:5760"


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("serial:/dev/tty:1", "baud rate 1 not one of"),
        ("serial:/dev/ttyAMA0:fast", "not a number"),
        ("serial:/dev/ttyAMA0", "serial:DEVICE:BAUD"),
        ("udpin:0.0.0.0:x", "not a number"),
        ("udpin", "SCHEME"),
        ("uart:ttyS0:57600", "scheme 'uart'"),
    ],
)
def test_bad_urls_are_named(url: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        parse_address(url)


@pytest.mark.parametrize(
    "url",
    ["serial:/dev/ttyAMA0:921600", "serial:///dev/ttyAMA0:921600", "/dev/ttyAMA0,921600"],
)
def test_serial_spellings_of_both_backends(url: str) -> None:
    a = parse_address(url)
    assert (a.scheme, a.host, a.port, a.is_serial) == ("serial", "/dev/ttyAMA0", 921600, True)
    assert a.url() == "serial:/dev/ttyAMA0:921600"
    assert a.mavsdk_url() == "serial:///dev/ttyAMA0:921600"
