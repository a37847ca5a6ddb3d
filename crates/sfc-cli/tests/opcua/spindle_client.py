"""An independent OPC UA client (asyncua) against `sfc run examples/spindle/spindle.st --opcua …`
(SecurityPolicy None, anonymous): the mechanism `Rev` as a chart of its own, its actions' Q
and A, the T of a step left, and the error record of error 4.05 (KM2's contact never comes).

Usage: spindle_client.py URL

Prints one JSON object on standard output with what it saw; the Rust test judges it.
"""

import asyncio
import json
import sys
import time

from asyncua import Client, ua

NS = "urn:sfc:run"


async def type_name(c, node):
    return (await c.get_node(await node.read_type_definition()).read_browse_name()).Name


async def names(node):
    return sorted([(await n.read_browse_name()).Name for n in await node.get_children()])


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
        rev = await chart.get_child([f"{ns}:Rev"])
        report["types"] = {
            "Main": await type_name(c, main),
            "Chart": await type_name(c, chart),
            "Rev": await type_name(c, rev),
        }
        report["chart"] = await names(chart)
        report["rev"] = await names(rev)
        # The type of the mechanism's chart and what it declares (HasTypeDefinition → SfcType).
        sfc_type = c.get_node(await rev.read_type_definition())
        report["sfc_type_members"] = await names(sfc_type)
        supers = await sfc_type.get_references(refs=ua.ObjectIds.HasSubtype, direction=ua.BrowseDirection.Inverse)
        report["sfc_type_supertype"] = [r.BrowseName.Name for r in supers]
        child = lambda *p: rev.get_child([f"{ns}:{x}" for x in p])
        for folder in ("Steps", "Transitions", "Actions"):
            f = await child(folder)
            report[folder] = await names(f)
            first = (await f.get_children())[0]
            report["types"][folder] = await type_name(c, first)
        report["function_block"] = await (await child("FunctionBlock")).read_value()
        read = lambda *p: _read(child, *p)
        report["before"] = {n: await read(n) for n in ("LastError", "LastErrorCode", "LastErrorStep", "ErrorCount")}
        report["never_active_T"] = await read("Steps", "Err404", "T")

        inp = lambda n: main.get_child([f"{ns}:Inputs", f"{ns}:{n}"])

        async def write(n, v):
            await (await inp(n)).write_value(ua.DataValue(ua.Variant(v, ua.VariantType.Boolean)))

        # Spindle on clockwise, then the reversal: Rev leaves Idle for OpenKM1.
        await write("StartCwButton", True)
        await write("KM1Contact", True)
        await asyncio.sleep(0.2)
        await write("ReverseButton", True)
        await until("Rev.OpenKM1 active", lambda: read("Steps", "OpenKM1", "X"))
        report["actions_in_OpenKM1"] = {
            a: [await read("Actions", a, "Q"), await read("Actions", a, "A")] for a in ("Busy", "Done", "Fault")
        }
        # KM1 drops out: OpenKM1 is left; its T keeps the time it was active.
        await asyncio.sleep(0.3)
        await write("KM1Contact", False)
        await until("Rev.OpenKM1 left", lambda: _not(read("Steps", "OpenKM1", "X")))
        t1 = await read("Steps", "OpenKM1", "T")
        await asyncio.sleep(0.3)
        report["OpenKM1_left"] = {
            "X": await read("Steps", "OpenKM1", "X"),
            "T": t1,
            "T later": await read("Steps", "OpenKM1", "T"),
        }
        # KM2's contact never comes: after its supervision time CloseKM2 makes error 4.05.
        await until("an error record", lambda: read("ErrorCount"), timeout=15)
        await until("Rev.Err405 active", lambda: read("Steps", "Err405", "X"))
        report["after"] = {n: await read(n) for n in ("LastError", "LastErrorCode", "LastErrorStep", "ErrorCount")}
        report["fault_action"] = [await read("Actions", "Fault", "Q"), await read("Actions", "Fault", "A")]
        report["CloseKM2_T"] = await read("Steps", "CloseKM2", "T")
    return report


async def _read(child, *path):
    return await (await child(*path)).read_value()


async def _not(aw):
    return not await aw


def main():
    print(json.dumps(asyncio.run(run(sys.argv[1])), default=str))


if __name__ == "__main__":
    main()
