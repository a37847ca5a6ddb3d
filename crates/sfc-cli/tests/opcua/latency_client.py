"""How long a change takes from a Modbus write of an input to an OPC UA subscriber, on
`tests/run/echo.st` (the lamp follows the button in the next scan).

Usage: latency_client.py OPCUA_URL MODBUS_PORT CHANGES PUBLISH_MS

Subscribes to Echo.Lamp with the given publishing interval (sampling interval 0), then toggles
the button (coil 32768) CHANGES times; each time, the time from the write's answer to the
notification of the lamp's new value. Prints one JSON object: the revised publishing
interval, and the latencies in ms (sorted).
"""

import asyncio
import json
import random
import sys
import time

from asyncua import Client, ua
from asyncua.common.subscription import Subscription
from pymodbus.client import AsyncModbusTcpClient


class Lamp:
    def __init__(self):
        self.value = None
        self.changed = asyncio.Event()
        self.at = 0.0

    def datachange_notification(self, node, val, data):
        self.value = val
        self.at = time.monotonic()
        self.changed.set()


async def main(url, port, changes, publish_ms):
    m = AsyncModbusTcpClient("127.0.0.1", port=port)
    await m.connect()
    async with Client(url) as c:
        ns = await c.get_namespace_index("urn:sfc:run")
        lamp = Lamp()
        params = ua.CreateSubscriptionParameters()
        params.RequestedPublishingInterval = publish_ms
        params.RequestedLifetimeCount = 10000
        params.RequestedMaxKeepAliveCount = 100
        params.Priority = 0
        params.PublishingEnabled = True
        params.MaxNotificationsPerPublish = 10000
        # Made by hand to read the publishing interval the server granted.
        sub = Subscription(c.uaclient.session, params, lamp)
        revised = (await sub.init()).RevisedPublishingInterval
        await sub.subscribe_data_change(c.get_node(f"ns={ns};s=Echo.Lamp"), sampling_interval=0)
        await asyncio.sleep(0.5)
        latencies, missed = [], 0
        state = bool(lamp.value)
        for _ in range(changes):
            state = not state
            lamp.changed.clear()
            await m.write_coil(32768, state)
            sent = time.monotonic()
            # A change that never comes is a failure; a slow one (a loaded machine) only a figure.
            deadline = sent + 10.0
            while lamp.value != state and time.monotonic() < deadline:
                lamp.changed.clear()
                try:
                    await asyncio.wait_for(lamp.changed.wait(), timeout=max(0.0, deadline - time.monotonic()))
                except asyncio.TimeoutError:
                    break
            if lamp.value == state:
                latencies.append((lamp.at - sent) * 1000.0)
            else:
                missed += 1
            # A pause of a few publishing intervals between changes, of a random length: a whole
            # number of intervals would put every change at the same phase of the server's
            # publishing timer (just after a publish: the worst case every time).
            await asyncio.sleep(random.uniform(2, 4) * publish_ms / 1000.0)
        await sub.delete()
    m.close()
    latencies.sort()
    print(json.dumps({"revised_publishing_ms": revised, "latencies_ms": latencies, "missed": missed}))


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])))
