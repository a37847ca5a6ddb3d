"""An independent OPC UA client (asyncua) against `sfc run crates/sfc-cli/tests/nested/machine.st
--opcua …` (SecurityPolicy None, anonymous): charts inside charts two levels deep. Main's chart
holds a node per nested chart instance — the lift (an SFC function block instance), the chart of
its action ACT_Load, and the chart of its gripper's action ACT_Grip — each with its steps, whose X
follow the run once Start is written.

Usage: nested_client.py URL

Prints one JSON object on standard output with what it saw; the Rust test judges it.
"""

import asyncio
import json
import sys
import time

from asyncua import Client, ua

NS = "urn:sfc:run"


async def names(node):
    return sorted([(await n.read_browse_name()).Name for n in await node.get_children()])


async def type_name(c, node):
    return (await c.get_node(await node.read_type_definition()).read_browse_name()).Name


async def until(what, read, timeout=10.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if await read():
            return True
        await asyncio.sleep(0.02)
    raise TimeoutError(what)


async def run(url):
    report = {}
    async with Client(url=url, timeout=10) as c:
        ns = await c.get_namespace_index(NS)
        main = await c.nodes.objects.get_child([f"{ns}:Main"])
        chart = await main.get_child([f"{ns}:Chart"])
        report["chart"] = await names(chart)
        report["steps"] = {}
        report["types"] = {}
        report["node_ids"] = {}
        for inst in ("Lift", "Lift.ACT_Load", "Lift.Grip.ACT_Grip"):
            node = await chart.get_child([f"{ns}:{inst}"])
            report["types"][inst] = await type_name(c, node)
            report["node_ids"][inst] = node.nodeid.Identifier
            steps = await node.get_child([f"{ns}:Steps"])
            report["steps"][inst] = await names(steps)
        report["steps"]["Main"] = await names(await chart.get_child([f"{ns}:Steps"]))

        def x(inst, step):
            async def read():
                node = await chart.get_child([f"{ns}:{inst}", f"{ns}:Steps", f"{ns}:{step}", f"{ns}:X"])
                return await node.read_value()
            return read

        start = await main.get_child([f"{ns}:Inputs", f"{ns}:Start"])
        await start.write_value(ua.DataValue(ua.Variant(True, ua.VariantType.Boolean)))
        await until("Lift.Grip.ACT_Grip.Holding active", x("Lift.Grip.ACT_Grip", "Holding"))
        await until("Lift.Raise active", x("Lift", "Raise"))
        report["active"] = {
            "Lift.Raise": await x("Lift", "Raise")(),
            "Lift.Home": await x("Lift", "Home")(),
            "Lift.ACT_Load.Done": await x("Lift.ACT_Load", "Done")(),
            "Lift.Grip.ACT_Grip.Holding": await x("Lift.Grip.ACT_Grip", "Holding")(),
            "Lift.Grip.ACT_Grip.Open": await x("Lift.Grip.ACT_Grip", "Open")(),
        }
        holding = await chart.get_child([f"{ns}:Lift.Grip.ACT_Grip", f"{ns}:Steps", f"{ns}:Holding", f"{ns}:X"])
        report["holding_x_id"] = holding.nodeid.Identifier
    print(json.dumps(report, sort_keys=True))


asyncio.run(run(sys.argv[1]))
