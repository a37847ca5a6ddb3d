"""Reads the outputs of `tests/run/runaway.st` (POU Filler) through OPC UA (a read, and a
subscription kept open for the whole run) and through Modbus (the outputs and the status block),
on request, so the Rust test can compare them with the monitor and `--report` in each state.

Usage: views_client.py OPCUA_URL MODBUS_PORT

Standard input, one command per line:
  snap STATE   wait (at most 10 s) until OPC UA's Runtime/State (read and subscribed) and the
               Modbus status block all say STATE, then print one JSON line with every view
  quit         close and exit
"""

import asyncio
import json
import struct
import sys
import time

from asyncua import Client, ua
from pymodbus.client import ModbusTcpClient

NS_URI = "urn:sfc:run"
OUTPUTS = ["Pump", "Vent", "Pressure", "Batch"]
STATES = {"RUN": 0, "STOP": 1, "FAULT": 2}


def modbus_view(m):
    """The outputs as Modbus shows them (big word order) and the status block (40300…)."""
    coils = m.read_coils(0, count=2).bits[:2]
    regs = m.read_holding_registers(2, count=4).registers
    pressure = struct.unpack(">f", struct.pack(">HH", regs[0], regs[1]))[0]
    batch = regs[2] << 16 | regs[3]
    s = m.read_input_registers(40300, count=8).registers
    status = {
        "state": s[0],
        "halted": s[1],
        "scan": s[2] << 48 | s[3] << 32 | s[4] << 16 | s[5],
        "fault": s[6],
        "faults": s[7],
    }
    return {"Pump": coils[0], "Vent": coils[1], "Pressure": pressure, "Batch": batch}, status


class Latest:
    """The newest value of each subscribed node."""

    def __init__(self, names):
        self.names = names
        self.values = {}

    def datachange_notification(self, node, val, data):
        self.values[self.names[node.nodeid.to_string()]] = val


async def main(url, port):
    m = ModbusTcpClient("127.0.0.1", port=port)
    m.connect()
    async with Client(url) as c:
        ns = await c.get_namespace_index(NS_URI)
        nodes = {n: c.get_node(f"ns={ns};s=Filler.{n}") for n in OUTPUTS}
        nodes["State"] = c.get_node(f"ns={ns};s=Filler/Runtime/State")
        nodes["ScanCount"] = c.get_node(f"ns={ns};s=Filler/Runtime/ScanCount")
        nodes["Halted"] = c.get_node(f"ns={ns};s=Filler/Runtime/Halted")
        latest = Latest({n.nodeid.to_string(): name for name, n in nodes.items()})
        sub = await c.create_subscription(20, latest)
        await sub.subscribe_data_change(list(nodes.values()))
        loop = asyncio.get_running_loop()
        while True:
            line = (await loop.run_in_executor(None, sys.stdin.readline)).split()
            if not line or line[0] == "quit":
                break
            want = line[1]
            deadline = time.monotonic() + 10
            while True:
                read = {name: await n.read_value() for name, n in nodes.items()}
                outputs, status = modbus_view(m)
                settled = (
                    read["State"] == want
                    and latest.values.get("State") == want
                    and status["state"] == STATES[want]
                    # The subscription has caught up with the read.
                    and all(latest.values.get(n) == read[n] for n in read)
                )
                if settled or time.monotonic() > deadline:
                    break
                await asyncio.sleep(0.05)
            print(json.dumps({"settled": settled, "opcua_read": read, "opcua_subscription": latest.values,
                              "modbus": outputs, "status": status}), flush=True)
    m.close()


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], int(sys.argv[2])))
