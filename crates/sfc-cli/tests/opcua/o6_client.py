"""A second, independent OPC UA client (o6, on open62541) against
`sfc run examples/carwash/carwash.st --opcua … --opcua-allow-none`.

Usage: o6_client.py open URL                  (SecurityPolicy None, anonymous)
       o6_client.py user URL USER PASSWORD PKI CLIENT_DIR
                                              (Basic256Sha256 SignAndEncrypt, a user)

Prints one JSON object as the last line of standard output with what it saw; the Rust test
judges it (o6 prints a banner on standard output when imported, hence "last line"). An
unexpected exception ends the script with a message on standard error and exit status 1.

Notes on o6 (2.2.0):
- Node ids are written `nsu=urn:sfc:run;s=…`: o6 resolves `ns=N` against its own process-wide
  namespace registry (where index 2 is some companion specification), not the server's
  namespace array, so the namespace is named by its URI.
- The client runs its own event loop on a worker thread: every call below is synchronous,
  and monitored-item callbacks run on that thread.
- o6 refuses to send a password the endpoint does not ask to encrypt unless
  `allowNonePolicyPassword` is set; the user mode sets it to show that the server refuses user
  names on the None endpoint itself, whatever the client would send.
"""

import json
import sys
import threading
import time
import traceback

import o6

NSU = "nsu=urn:sfc:run;s="
WASH = NSU + "CarWash"
RUNTIME = WASH + "/Runtime"
SPRAYING_X = WASH + "/Steps/Spraying/X"
OBJECTS = "i=85"
ALL_FIELDS = o6.ns.ns0.datatypes.BrowseResultMask.ALL


def status_name(code):
    """`BAD_NOT_WRITABLE` → `BadNotWritable`, the spelling of the OPC UA specification (and of
    asyncua's exception names), so both clients' reports read alike."""
    name = o6.StatusCode(int(code)).name or f"0x{int(code):08X}"
    return "".join(part.capitalize() for part in name.split("_"))


def plain(value):
    """A value read through o6 (numpy scalars for numbers) as a JSON-able Python value."""
    if hasattr(value, "item"):
        return value.item()
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    return str(value)


def children(client, node):
    """Browse `node` (hierarchical references, forward): {browse name: ExpandedNodeId}."""
    return {r.browseName.name: r.nodeId for r in client.browse(node, resultMask=ALL_FIELDS)}


def connect(url, **kwargs):
    """A connected client without o6's default 100 ms subscription (we make our own)."""
    client = o6.Client(url, **kwargs)
    client.connect(createDefaultSubscription=False)
    return client


def open_session(url):
    report = {"client": "o6"}
    client = connect(url)
    try:
        # Browse Objects → CarWash → its folders, and the chart's steps; names in the order
        # the server returns them.
        browse = {}
        objects = children(client, OBJECTS)
        browse["Objects"] = list(objects)
        wash = children(client, objects["CarWash"])
        browse["CarWash"] = list(wash)
        sections = {name: children(client, wash[name]) for name in ("Inputs", "Outputs") if name in wash}
        for name, nodes in sections.items():
            browse[name] = list(nodes)
        chart = children(client, wash["Chart"])
        browse["Chart"] = list(chart)
        browse["Steps"] = list(children(client, chart["Steps"]))
        report["browse"] = browse

        # Every variable under Inputs and Outputs, read through the node ids the browse gave.
        report["values"] = {
            name: plain(client.read(node)) for nodes in sections.values() for name, node in nodes.items()
        }
        report["state"] = plain(client.read(RUNTIME + "/State"))
        report["scan_count"] = plain(client.read(RUNTIME + "/ScanCount"))

        # A 50 ms subscription on Spraying.X; its data changes, in order.
        changes, first, became_true = [], threading.Event(), threading.Event()

        def on_change(value):  # on o6's worker thread
            changes.append(bool(value))
            first.set()
            if value:
                became_true.set()

        sub = client.createSubscription(publishingInterval=50.0)
        report["publishing_interval"] = plain(sub.publishingInterval)
        client.monitor(SPRAYING_X, on_change, samplingInterval=50.0, subscription=sub)
        first.wait(2.0)  # the initial value (FALSE) comes first

        # Start a wash: CarPresent, AtHome, then StartButton (Boolean variants). An output is
        # not writable.
        report["writes"] = {}
        for name in ("CarPresent", "AtHome", "StartButton", "SprayValve"):
            report["writes"][name] = status_name(client.write(WASH + "." + name, o6.Boolean(True)))

        # Methods need an authenticated user with the admin role.
        report["anonymous_halt"] = status_name(client.call(RUNTIME, RUNTIME + "/Halt")[0])

        report["spraying_seen"] = became_true.wait(5.0)
        report["spraying_changes"] = list(changes)
        report["SprayValve"] = plain(client.read(WASH + ".SprayValve"))
        report["state_after"] = plain(client.read(RUNTIME + "/State"))
        sub.delete()
    finally:
        client.disconnect()
    return report


def user_session(url, user, password, pki, client_dir):
    """A user over Basic256Sha256 SignAndEncrypt with a client certificate o6 makes: refused on
    the None endpoint, untrusted first (the server files the certificate under rejected/),
    trusted by moving it to trusted/, then Halt, Continue and a write; a wrong password."""
    from pathlib import Path
    import shutil

    report = {"client": "o6"}
    # What the None endpoint offers: no user name (a password could travel in clear there).
    probe = o6.Client(url)
    probe.connect(noSession=True)
    try:
        for ep in probe.getEndpoints(url):
            if ep.securityPolicyUri.endswith("#None"):
                report["none_user_tokens"] = sorted(t.policyId for t in ep.userIdentityTokens if int(t.tokenType) == 1)
    finally:
        probe.disconnect()
    try:
        connect(url, username=user, password=password, allowNonePolicyPassword=True).disconnect()
        report["none_login"] = "Good"
    except o6.StatusCodeError as e:
        report["none_login"] = status_name(e.code)

    client_dir = Path(client_dir)
    client_dir.mkdir(parents=True, exist_ok=True)
    app_uri = "urn:sfc:test:o6"
    key, cert = o6.util.createSelfSignedCertificate(appUri=app_uri, commonName="sfc test o6 client")
    server_cert = (Path(pki) / "own" / "cert.der").read_bytes()

    def secure(pw):
        return connect(
            url,
            certificate=cert,
            privateKey=key,
            trustList=[server_cert],
            securityMode=int(o6.SecurityMode.SIGN_AND_ENCRYPT),
            securityPolicy=o6.SecurityPolicy.BASIC256SHA256.value,
            applicationUri=app_uri,
            username=user,
            password=pw,
        )

    # 1. Not trusted yet: refused, filed under rejected/; the operator moves it to trusted/.
    try:
        secure(password).disconnect()
        report["untrusted"] = "Good"
    except o6.StatusCodeError as e:
        report["untrusted"] = status_name(e.code)
    rejected = sorted((Path(pki) / "rejected").glob("*.der"))
    report["rejected_files"] = len(rejected)
    for f in rejected:
        shutil.move(str(f), str(Path(pki) / "trusted" / f.name))
    # 2. Trusted: the user halts, continues and writes.
    client = secure(password)
    report["login"] = "Good"
    try:
        halted = RUNTIME + "/Halted"
        report["state"] = plain(client.read(RUNTIME + "/State"))
        report["halt"] = status_name(client.call(RUNTIME, RUNTIME + "/Halt")[0])
        time.sleep(0.5)  # applied by the scan thread
        report["halted_after_halt"] = plain(client.read(halted))
        report["continue"] = status_name(client.call(RUNTIME, RUNTIME + "/Continue")[0])
        time.sleep(0.5)
        report["halted_after_continue"] = plain(client.read(halted))
        report["user_write"] = status_name(client.write(WASH + ".DryerSelect", o6.Boolean(True)))
    finally:
        client.disconnect()
    # 3. A wrong password is refused.
    try:
        secure(password + "x").disconnect()
        report["wrong_password"] = "Good"
    except o6.StatusCodeError as e:
        report["wrong_password"] = status_name(e.code)
    return report


def main():
    if len(sys.argv) < 3 or sys.argv[1] not in ("open", "user") or (sys.argv[1] == "user" and len(sys.argv) != 7):
        sys.exit(__doc__.split("\n\n")[1])
    try:
        if sys.argv[1] == "open":
            report = open_session(sys.argv[2])
        else:
            report = user_session(*sys.argv[2:7])
    except Exception as e:  # noqa: BLE001 - any failure is the test's to report
        traceback.print_exc()
        sys.exit(f"o6_client.py {sys.argv[1]}: unexpected {type(e).__name__}: {e}")
    sys.stdout.flush()
    print(json.dumps(report), flush=True)


if __name__ == "__main__":
    main()
