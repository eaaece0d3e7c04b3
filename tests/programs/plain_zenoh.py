"""A program that knows only `zenoh` and `msgpack` and docs/wire-format.md.

plain_zenoh.py ENDPOINT SPACE write   writes one triple, prints the store's ack
plain_zenoh.py ENDPOINT SPACE watch   prints '+ KEY' / '- KEY' for battery levels until stdin closes
"""

import json
import sys
import uuid

import msgpack
import zenoh

AC = "https://w3id.org/tspace/selfconfig#"


def session(endpoint: str) -> zenoh.Session:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    return zenoh.open(conf)


def write(s: zenoh.Session, space: str) -> None:
    changeset = {
        "v": 1,
        "id": uuid.uuid4().hex,
        "agent": "plain-zenoh",
        "ts": str(s.new_timestamp()),
        "prefixes": {"ac": AC},
        "add": [[f"<{AC}robot9_battery>", f"<{AC}battery_level>", '"low"']],
    }
    for reply in s.get(f"tspace/{space}/@/write", payload=msgpack.packb(changeset), timeout=5):
        print(json.dumps(msgpack.unpackb(reply.ok.payload.to_bytes())), flush=True)


def watch(s: zenoh.Session, space: str) -> None:
    def show(sample: zenoh.Sample) -> None:
        sign = "+" if sample.kind == zenoh.SampleKind.PUT else "-"
        print(f"{sign} {sample.key_expr}", flush=True)

    with s.declare_subscriber(f"tspace/{space}/t/*/ac:battery_level/*", show):
        print("ready", flush=True)
        sys.stdin.read()


if __name__ == "__main__":
    endpoint, space, mode = sys.argv[1:4]
    with session(endpoint) as s:
        write(s, space) if mode == "write" else watch(s, space)
    print("space imported" if "space" in sys.modules else "space not imported", flush=True)
