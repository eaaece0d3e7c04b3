"""POST to the HMI as its own page does: with the session's cookie and token, and its Origin."""

from __future__ import annotations

import json
import urllib.error
import urllib.request


def hmi_post(port: int, path: str, body: dict) -> tuple[int, dict]:
    """Load the page (for its session), then POST `body`; return the status and the answer."""
    base = f"http://127.0.0.1:{port}"
    with urllib.request.urlopen(f"{base}/", timeout=10) as reply:
        cookie = reply.headers["Set-Cookie"].split(";")[0]
        token = reply.read().decode().split('name="hmi-token" content="')[1].split('"')[0]
    request = urllib.request.Request(
        f"{base}{path}",
        data=json.dumps(body).encode(),
        headers={
            "Content-Type": "application/json",
            "Origin": base,
            "Cookie": cookie,
            "X-HMI-Token": token,
        },
    )
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, json.load(reply)
    except urllib.error.HTTPError as exc:
        return exc.code, json.load(exc)
