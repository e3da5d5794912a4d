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
    [("serial:/dev/tty:1", "scheme"), ("udpin:0.0.0.0:x", "not a number"), ("udpin", "SCHEME")],
)
def test_bad_urls_are_named(url: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        parse_address(url)
