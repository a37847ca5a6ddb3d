"""An independent OPC UA client (asyncua) against `sfc run examples/carwash/carwash.st --opcua …`.

Usage: carwash_client.py open URL            (SecurityPolicy None, anonymous)
       carwash_client.py secure URL PKI USER PASSWORD CLIENT_DIR
       carwash_client.py roles URL PKI CLIENT_DIR  (users reader, operator, boss: password pw-NAME)
       carwash_client.py load URL CLIENTS SECONDS

Prints one JSON object on standard output with what it saw; the Rust test judges it.
"""

import asyncio
import json
import shutil
import sys
import time
from pathlib import Path

from asyncua import Client, ua

NS = "urn:sfc:run"


async def type_name(c, node):
    """The browse name of a node's HasTypeDefinition."""
    return (await c.get_node(await node.read_type_definition()).read_browse_name()).Name


async def browse(c):
    """Every variable under Inputs/Outputs/Locals/Globals with type, value and address; every
    step with X and T; every transition with its guard."""
    ns = await c.get_namespace_index(NS)
    root = await c.nodes.objects.get_child([f"{ns}:CarWash"])
    out = {"variables": {}, "steps": {}, "transitions": {}, "runtime": {}}
    for section in await root.get_children():
        sname = (await section.read_browse_name()).Name
        if sname in ("Inputs", "Outputs", "Locals", "Globals"):
            for v in await section.get_children():
                name = (await v.read_browse_name()).Name
                dtype = await v.read_data_type()
                dtype_name = (await c.get_node(dtype).read_browse_name()).Name
                props = {}
                for p in await v.get_properties():
                    props[(await p.read_browse_name()).Name] = await p.read_value()
                value = await v.read_value()
                out["variables"][name] = {
                    "section": sname,
                    "type": dtype_name,
                    "value": value,
                    "iec": props.get("IecType"),
                    "address": props.get("Address"),
                    "writable": bool((await v.read_attribute(ua.AttributeIds.AccessLevel)).Value.Value & 2),
                }
    chart = await root.get_child([f"{ns}:Chart"])
    out["types"] = {"Chart": await type_name(c, chart)}
    out["actions"] = {}
    for a in await (await chart.get_child([f"{ns}:Actions"])).get_children():
        name = (await a.read_browse_name()).Name
        out["actions"][name] = {"type": await type_name(c, a)}
    for s in await (await chart.get_child([f"{ns}:Steps"])).get_children():
        out["types"]["step"] = await type_name(c, s)
        name = (await s.read_browse_name()).Name
        x = await (await s.get_child([f"{ns}:X"])).read_value()
        t = await (await s.get_child([f"{ns}:T"])).read_value()
        out["steps"][name] = {"X": x, "T": t}
    for t in await (await chart.get_child([f"{ns}:Transitions"])).get_children():
        name = (await t.read_browse_name()).Name
        dv = await (await t.get_child([f"{ns}:Guard"])).read_data_value(raise_on_bad_status=False)
        out["transitions"][name] = {"guard": dv.Value.Value, "status": dv.StatusCode.name}
    rt = await root.get_child([f"{ns}:Runtime"])
    for v in await rt.get_children():
        if await v.read_node_class() == ua.NodeClass.Variable:
            out["runtime"][(await v.read_browse_name()).Name] = await v.read_value()
    return out, ns, root


async def write(node, value, vtype):
    try:
        await node.write_value(ua.DataValue(ua.Variant(value, vtype)))
        return "Good"
    except ua.UaStatusCodeError as e:
        return type(e).__name__


class Changes:
    def __init__(self):
        self.values = []

    def datachange_notification(self, node, val, data):
        self.values.append(val)


async def open_session(url):
    report = {}
    async with Client(url=url, timeout=10) as c:
        seen, ns, root = await browse(c)
        report["browse"] = seen
        inp = lambda n: root.get_child([f"{ns}:Inputs", f"{ns}:{n}"])
        x = await root.get_child([f"{ns}:Chart", f"{ns}:Steps", f"{ns}:Spraying", f"{ns}:X"])
        changes = Changes()
        sub = await c.create_subscription(100, changes)
        await sub.subscribe_data_change(x, sampling_interval=100)
        await asyncio.sleep(0.5)
        report["writes"] = {
            "CarPresent": await write(await inp("CarPresent"), True, ua.VariantType.Boolean),
            "AtHome": await write(await inp("AtHome"), True, ua.VariantType.Boolean),
            "StartButton as Int16": await write(await inp("StartButton"), 1, ua.VariantType.Int16),
        }
        await asyncio.sleep(0.3)
        report["writes"]["StartButton"] = await write(await inp("StartButton"), True, ua.VariantType.Boolean)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and True not in changes.values:
            await asyncio.sleep(0.05)
        report["spraying_changes"] = changes.values
        # Spraying's actions: their action control's Q and A; Idle, left, keeps its last T.
        acts = lambda n, f: root.get_child([f"{ns}:Chart", f"{ns}:Actions", f"{ns}:{n}", f"{ns}:{f}"])
        report["actions_in_spraying"] = {
            n: [await (await acts(n, "Q")).read_value(), await (await acts(n, "A")).read_value()]
            for n in ("SprayValve", "Travel", "Brush", "FaultLamp")
        }
        idle = lambda f: root.get_child([f"{ns}:Chart", f"{ns}:Steps", f"{ns}:Idle", f"{ns}:{f}"])
        t1 = await (await idle("T")).read_value()
        await asyncio.sleep(0.3)
        report["idle_left"] = {"X": await (await idle("X")).read_value(), "T": t1, "T later": await (await idle("T")).read_value()}
        report["StartButton"] = await (await inp("StartButton")).read_value()
        out = await root.get_child([f"{ns}:Outputs", f"{ns}:SprayValve"])
        report["SprayValve"] = await out.read_value()
        report["writes"]["SprayValve"] = await write(out, False, ua.VariantType.Boolean)
        rt = await root.get_child([f"{ns}:Runtime"])
        try:
            await rt.call_method(f"{ns}:Halt")
            report["anonymous_halt"] = "Good"
        except ua.UaStatusCodeError as e:
            report["anonymous_halt"] = type(e).__name__
        await sub.delete()
    return report


async def client_certificate(client_dir):
    """A self-signed client certificate in `client_dir`: (key, cert, application URI)."""
    from asyncua.crypto.cert_gen import setup_self_signed_certificate
    from cryptography.x509.oid import ExtendedKeyUsageOID

    client_dir = Path(client_dir)
    client_dir.mkdir(parents=True, exist_ok=True)
    key, cert = client_dir / "key.pem", client_dir / "cert.der"
    app_uri = "urn:sfc:test:client"
    await setup_self_signed_certificate(
        key, cert, app_uri, "localhost", [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": "sfc test client"}
    )
    return key, cert, app_uri


async def secure_session(url, pki, user, password, client_dir):
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256

    key, cert, app_uri = await client_certificate(client_dir)
    report = {}

    async def connect(mode, with_user=True):
        c = Client(url=url, timeout=10)
        c.application_uri = app_uri
        if with_user:
            c.set_user(user)
            c.set_password(password)
        await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key), mode=mode)
        return c

    # 1. Not trusted yet: refused, and the certificate lands in the PKI's rejected folder.
    try:
        c = await connect(ua.MessageSecurityMode.SignAndEncrypt)
        await c.connect()
        await c.disconnect()
        report["untrusted"] = "connected"
    except Exception as e:
        report["untrusted"] = type(e).__name__
    rejected = sorted((Path(pki) / "rejected").glob("*.der"))
    report["rejected_files"] = len(rejected)
    # 2. The operator trusts it (moves it to trusted/), as docs/runtime.md says.
    for f in rejected:
        shutil.move(str(f), str(Path(pki) / "trusted" / f.name))
    # 3. SignAndEncrypt with the user: read, halt, continue.
    c = await connect(ua.MessageSecurityMode.SignAndEncrypt)
    async with c:
        ns = await c.get_namespace_index(NS)
        root = await c.nodes.objects.get_child([f"{ns}:CarWash"])
        rt = await root.get_child([f"{ns}:Runtime"])
        halted = await rt.get_child([f"{ns}:Halted"])
        report["state"] = await (await rt.get_child([f"{ns}:State"])).read_value()
        await rt.call_method(f"{ns}:Halt")
        await asyncio.sleep(0.5)
        report["halted_after_halt"] = await halted.read_value()
        await rt.call_method(f"{ns}:Continue")
        await asyncio.sleep(0.5)
        report["halted_after_continue"] = await halted.read_value()
        inp = await root.get_child([f"{ns}:Inputs", f"{ns}:DryerSelect"])
        report["user_write"] = await write(inp, True, ua.VariantType.Boolean)
    # 4. Sign only, same user.
    c = await connect(ua.MessageSecurityMode.Sign)
    async with c:
        ns = await c.get_namespace_index(NS)
        report["sign_state"] = await c.nodes.objects.get_child([f"{ns}:CarWash", f"{ns}:Runtime", f"{ns}:State"])
        report["sign_state"] = await report["sign_state"].read_value()
    # 5. A wrong password is refused.
    try:
        c = Client(url=url, timeout=10)
        c.application_uri = app_uri
        c.set_user(user)
        c.set_password(password + "x")
        await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key), mode=ua.MessageSecurityMode.SignAndEncrypt)
        await c.connect()
        await c.disconnect()
        report["wrong_password"] = "connected"
    except Exception as e:
        report["wrong_password"] = type(e).__name__
    return report


async def roles(url, pki, client_dir):
    """What each kind of session may do: anonymous on the None endpoint and on
    Basic256Sha256 SignAndEncrypt, and the users `reader` (role read), `operator` (operate) and
    `boss` (admin): read, write an input, read the input's UserAccessLevel, call Halt."""
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256

    key, cert, app_uri = await client_certificate(client_dir)

    async def client(user, secure):
        c = Client(url=url, timeout=10)
        c.application_uri = app_uri
        if user:
            c.set_user(user)
            c.set_password(f"pw-{user}")
        if secure:
            await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key),
                                 mode=ua.MessageSecurityMode.SignAndEncrypt)
        return c

    # Trust the client's certificate first (the operator's move from rejected/ to trusted/).
    try:
        c = await client("boss", True)
        await c.connect()
        await c.disconnect()
    except Exception:
        pass
    for f in sorted((Path(pki) / "rejected").glob("*.der")):
        shutil.move(str(f), str(Path(pki) / "trusted" / f.name))

    async def session(user, secure):
        out = {}
        try:
            c = await client(user, secure)
            await c.connect()
        except Exception as e:
            return {"connect": type(e).__name__}
        try:
            ns = await c.get_namespace_index(NS)
            node = c.get_node(f"ns={ns};s=CarWash.DryerSelect")
            out["read"] = await (c.get_node(f"ns={ns};s=CarWash/Runtime/State")).read_value()
            out["write"] = await write(node, True, ua.VariantType.Boolean)
            level = (await node.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value
            out["user_writable"] = bool(level & 2)
            try:
                await c.get_node(f"ns={ns};s=CarWash/Runtime").call_method(f"{ns}:Halt")
                out["halt"] = "Good"
                await c.get_node(f"ns={ns};s=CarWash/Runtime").call_method(f"{ns}:Continue")
            except ua.UaStatusCodeError as e:
                out["halt"] = type(e).__name__
        finally:
            await c.disconnect()
        return out

    report = {}
    for user in (None, "reader", "operator", "boss"):
        for secure in (False, True):
            report[f"{user or 'anonymous'} {'secure' if secure else 'none'}"] = await session(user, secure)
    return report


async def load(url, clients, seconds):
    """`clients` sessions, each subscribed to every variable at 100 ms, for `seconds`."""
    counts = []

    async def one():
        c = Client(url=url, timeout=20)
        async with c:
            ns = await c.get_namespace_index(NS)
            root = await c.nodes.objects.get_child([f"{ns}:CarWash"])
            nodes = []
            for section in await root.get_children():
                if (await section.read_browse_name()).Name in ("Inputs", "Outputs", "Locals", "Globals"):
                    nodes.extend(await section.get_children())
            chart = await root.get_child([f"{ns}:Chart", f"{ns}:Steps"])
            for s in await chart.get_children():
                nodes.extend([await s.get_child([f"{ns}:X"]), await s.get_child([f"{ns}:T"])])
            h = Changes()
            sub = await c.create_subscription(100, h)
            await sub.subscribe_data_change(nodes, sampling_interval=100)
            await asyncio.sleep(seconds)
            counts.append(len(h.values))
            await sub.delete()

    await asyncio.gather(*(one() for _ in range(clients)))
    return {"clients": len(counts), "notifications": sum(counts)}


def main():
    mode, url = sys.argv[1], sys.argv[2]
    if mode == "open":
        report = asyncio.run(open_session(url))
    elif mode == "secure":
        report = asyncio.run(secure_session(url, *sys.argv[3:7]))
    elif mode == "roles":
        report = asyncio.run(roles(url, *sys.argv[3:5]))
    else:
        report = asyncio.run(load(url, int(sys.argv[3]), float(sys.argv[4])))
    print(json.dumps(report, default=str))


if __name__ == "__main__":
    main()
