"""Print the index (in argv order) of the etcd member that leads now, or -1.

etcd_leader.py ENDPOINT...   (run inside a host's namespace: the members' addresses are there)
"""

import asyncio
import sys

from space.store.etcd_client import EtcdClient


async def main(endpoints: list[str]) -> int:
    client = EtcdClient(endpoints)
    await client.open()
    try:
        leader = await client.leader()
    finally:
        await client.close()
    return -1 if leader is None else leader


if __name__ == "__main__":
    print(asyncio.run(main(sys.argv[1:])))
