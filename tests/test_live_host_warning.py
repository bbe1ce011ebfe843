"""Issue 22: a live server bound beyond loopback says who can see the run; loopback stays silent."""

from __future__ import annotations

import pytest

from bt_grasp.cli.run_cmd import exposure_warning
from bt_grasp.files.hosts import is_loopback


@pytest.mark.parametrize("host", ["127.0.0.1", "127.1.2.3", "::1", "localhost"])
def test_loopback_addresses_need_no_warning(host: str) -> None:
    assert is_loopback(host)


@pytest.mark.parametrize("host", ["0.0.0.0", "::", "10.0.0.5", "192.168.1.2", "myhost.example"])
def test_other_addresses_are_warned_about_with_the_tunnel_to_use(host: str) -> None:
    assert not is_loopback(host)
    text = exposure_warning(host)
    assert host in text and "no authentication" in text and "ssh -L" in text
