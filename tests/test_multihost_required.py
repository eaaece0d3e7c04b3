"""Where the multi-host tests cannot run, they skip, saying why; CI makes that a failure."""

import netns
import pytest
from netns import REQUIRE, require_netns


@pytest.fixture
def no_netns(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make namespaces unavailable, as for a developer without root."""
    monkeypatch.setattr(netns, "netns_unavailable", lambda: "network namespaces need root")


def test_without_namespaces_a_multihost_test_is_skipped_with_the_reason(no_netns, monkeypatch):
    monkeypatch.delenv(REQUIRE, raising=False)
    with pytest.raises(pytest.skip.Exception, match="need root"):
        require_netns()


def test_where_they_are_required_it_fails_instead(no_netns, monkeypatch):
    monkeypatch.setenv(REQUIRE, "1")
    with pytest.raises(pytest.fail.Exception, match=r"need root.*TSPACE_REQUIRE_NETNS=1"):
        require_netns()


def test_ci_requires_them():
    ci = (netns.REPO / ".ci" / "run").read_text()
    assert f"export {REQUIRE}=1" in ci
