"""Turn command-line style options into a `zenoh.Config`.

Every agent and CLI command goes through here so that `--connect`, `--listen`
and `--config` mean the same thing everywhere.
"""

from __future__ import annotations

import json
from pathlib import Path

import zenoh

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


def make_config(
    *,
    mode: str = "client",
    connect: list[str] | None = None,
    listen: list[str] | None = None,
    config_file: str | Path | None = None,
) -> zenoh.Config:
    """Build a Zenoh configuration.

    Args:
        mode: "client", "peer" or "router".
        connect: endpoints to connect to (default: the embedded router's endpoint
            for clients and peers, none for routers).
        listen: endpoints to listen on (routers default to `DEFAULT_ENDPOINT`).
        config_file: a Zenoh JSON5 configuration file read first; the options
            above override what it says.
    """
    conf = zenoh.Config.from_file(str(config_file)) if config_file else zenoh.Config()
    conf.insert_json5("mode", json.dumps(mode))
    if connect is None and mode != "router" and not config_file:
        connect = [DEFAULT_ENDPOINT]
    if listen is None and mode == "router" and not config_file:
        listen = [DEFAULT_ENDPOINT]
    if connect is not None:
        conf.insert_json5("connect/endpoints", json.dumps(connect))
    if listen is not None:
        conf.insert_json5("listen/endpoints", json.dumps(listen))
    if not config_file:
        # Explicit endpoints only: multicast scouting would make separate test
        # routers on one machine find each other and merge their spaces.
        conf.insert_json5("scouting/multicast/enabled", "false")
    return conf
