"""Load and soak driver for `sfc run examples/carwash/carwash.st --modbus … --opcua … --opcua-allow-none`.

Usage: soak_client.py OPCUA_URL MODBUS_PORT SECONDS

For SECONDS it runs, all at once:
  (a) Modbus TCP (pymodbus): 8 pollers, each reading, in turn and at least 5 ms apart, the
      outputs (coils 0..5, FC 1), the inputs (discrete inputs 0..6, FC 2) and the run's status
      block (input registers 40300..40307, FC 4); and one writer that steps the wash inputs
      through their coil window every ~200 ms (CarPresent, AtHome, StartButton, then
      StopButton), so the chart keeps moving Idle -> Spraying -> Idle;
  (b) 3 asyncua sessions, each subscribed (publishing and sampling 100 ms) to every variable
      under Inputs and Outputs and every step's X, reading Runtime/State and ScanCount once a
      second;
  (c) 2 o6 (open62541) sessions doing the same, each in a child process (`--o6-child`): o6
      ends its process after 10 minutes, so each child is replaced every 4 minutes (counted
      as `restarts`, not as errors); the new child subscribes before the old one is told to
      stop, so the load does not pause.

Before the clock starts, the o6 children are started and waited for until they have
subscribed (at most O6_SETUP s: importing o6 alone takes seconds of CPU), so that all the
load runs for SECONDS.

Errors, counted per kind: any exception; a Modbus exception response or a short answer; a
status block whose scan number goes back; a Bad status on a read or a data change that should
be Good; a subscription status change; a session with no data change for 5 s (the writer
changes inputs every 200 ms, so a silent subscription is a lost one); an o6 child that dies or
must be killed.

A progress line goes to standard error every 10 s; at the end one JSON line goes to standard
output (the Rust test judges it):
  {"seconds":..,"setup_seconds":..,"stop_seconds":..,"modbus":{"requests":..,"errors":..,…},
   "asyncua":{"sessions":3,"notifications":..,"errors":..,"reads":..},
   "o6":{"sessions":2,"notifications":..,"errors":..,"restarts":..,"reads":..},
   "errors":[the first 20 error messages]}
`seconds` is how long the load ran, `setup_seconds` how long the o6 children took to start
before it, `stop_seconds` how long closing everything took after it; `sessions` counts the
sessions whose subscription was made at least once; `requests` counts Modbus requests sent,
`reads` the OPC UA sessions' own reads.

Every wait is bounded (request timeouts, `asyncio.wait_for`, child processes killed after a
grace period), so the script stops at SECONDS and closes its sessions even if the server stops
answering: the stop takes well under a second against a healthy server and at most about
O6_STOP_GRACE (6 s) against a silent one; a hard stop (O6_SETUP + SECONDS + 40 s) prints the
report anyway.
"""

import asyncio
import json
import os
import signal
import sys
import threading
import time

# --- Shared counters -----------------------------------------------------------------------

MAX_MESSAGES = 20
MAX_MESSAGES_PER_KIND = 10  # so that a flood of one kind leaves room for the others
_messages = []
_messages_per_kind = {}
_messages_lock = threading.Lock()


def record(kind, message):
    """Keep the first MAX_MESSAGES error messages, at most MAX_MESSAGES_PER_KIND of a kind."""
    with _messages_lock:
        n = _messages_per_kind.get(kind, 0)
        if len(_messages) < MAX_MESSAGES and n < MAX_MESSAGES_PER_KIND:
            _messages.append(f"{kind}: {message}")
            _messages_per_kind[kind] = n + 1


class Tally:
    """Counters of one kind of client; threads (Modbus) and the event loop both update them."""

    def __init__(self, kind):
        self.kind = kind
        self.lock = threading.Lock()
        self.requests = 0
        self.notifications = 0
        self.errors = 0
        self.restarts = 0
        self.sessions = set()  # slots whose subscription was made at least once

    def request(self, n=1):
        with self.lock:
            self.requests += n

    def notification(self, n=1):
        with self.lock:
            self.notifications += n

    def error(self, message, n=1):
        with self.lock:
            self.errors += n
        record(self.kind, message)


def short(e):
    """An exception as `Type: message`, on one line."""
    text = " ".join(str(e).split())
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


# --- (a) Modbus ----------------------------------------------------------------------------

MODBUS_POLLERS = 8
POLL_GAP = 0.005  # seconds between two requests of one poller
WRITE_GAP = 0.2  # seconds between two writes of the writer
INPUT_WINDOW = 32768  # coil window of the %IX inputs (docs/runtime.md, "Modbus map")
STATUS_BASE = 40300  # the run's status block (input registers, FC 4)
# The writer's cycle: (coil offset in the input window, name, value). With a car present and
# the gantry home, StartButton starts a wash (Spraying); StopButton ends it (back to Idle).
WRITE_CYCLE = [
    (4, "CarPresent", True),
    (5, "AtHome", True),
    (0, "StartButton", True),
    (0, "StartButton", False),
    (3, "StopButton", True),
    (3, "StopButton", False),
]


def modbus_client(port):
    from pymodbus.client import ModbusTcpClient

    # One second per request and no retries: a silent server costs each call at most 1 s.
    return ModbusTcpClient("127.0.0.1", port=port, timeout=1, retries=0, reconnect_delay=0.1, reconnect_delay_max=1)


def modbus_poller(k, port, stop, tally):
    client = modbus_client(port)
    last_scan = None
    polls = [
        ("read_coils", 0, 6),  # SprayValve .. FaultLamp, %QX0.0..5
        ("read_discrete_inputs", 0, 7),  # StartButton .. DryerSelect, %IX0.0..6
        ("read_input_registers", STATUS_BASE, 8),  # state, halted, scan (4), fault, faults
    ]
    try:
        while not stop.is_set():
            for name, address, count in polls:
                if stop.is_set():
                    break
                tally.request()
                try:
                    r = getattr(client, name)(address, count=count)
                    if r.isError():
                        tally.error(f"poller {k}: {name}({address}, {count}): {r}")
                    elif name == "read_input_registers":
                        regs = r.registers
                        if len(regs) != count:
                            tally.error(f"poller {k}: {name}({address}, {count}): {len(regs)} registers")
                        else:
                            # The scan number (ULINT, big-endian word order) never goes back.
                            scan = (regs[2] << 48) | (regs[3] << 32) | (regs[4] << 16) | regs[5]
                            if last_scan is not None and scan < last_scan:
                                tally.error(f"poller {k}: scan number went back from {last_scan} to {scan}")
                            last_scan = scan
                    elif len(r.bits) < count:
                        tally.error(f"poller {k}: {name}({address}, {count}): {len(r.bits)} bits")
                except Exception as e:  # noqa: BLE001 - counted, then go on
                    tally.error(f"poller {k}: {name}({address}, {count}): {short(e)}")
                    stop.wait(0.1)  # do not spin on a refused or broken connection
                stop.wait(POLL_GAP)
    finally:
        client.close()


def modbus_writer(port, stop, tally):
    client = modbus_client(port)
    step = 0
    try:
        while not stop.is_set():
            offset, name, value = WRITE_CYCLE[step % len(WRITE_CYCLE)]
            step += 1
            tally.request()
            try:
                r = client.write_coil(INPUT_WINDOW + offset, value)
                if r.isError():
                    tally.error(f"writer: write_coil({INPUT_WINDOW + offset}, {value}) ({name}): {r}")
            except Exception as e:  # noqa: BLE001
                tally.error(f"writer: write_coil({INPUT_WINDOW + offset}, {value}) ({name}): {short(e)}")
            stop.wait(WRITE_GAP)
    finally:
        client.close()


# --- OPC UA nodes ---------------------------------------------------------------------------

NS_URI = "urn:sfc:run"
SUB_INTERVAL = 100.0  # ms, publishing and sampling
READ_EVERY = 1.0  # s, the sessions' own reads of Runtime/State and ScanCount
SILENCE = 5.0  # s without a data change: the subscription is counted as lost (once per silence)
SETUP_LIMIT = 15.0  # s an o6 child may take to connect, browse and subscribe


# --- (b) asyncua ---------------------------------------------------------------------------

ASYNCUA_SESSIONS = 3
ASYNCUA_TIMEOUT = 4.0  # s, each request
CLOSE_TIMEOUT = 1.5  # s, each of: delete the subscription, close the session


class AsyncuaHandler:
    """Counts data changes; a Bad value or a subscription status change is an error."""

    def __init__(self, k, tally):
        self.k, self.tally = k, tally
        self.last = time.monotonic()

    def datachange_notification(self, node, val, data):
        self.last = time.monotonic()
        self.tally.notification()
        status = data.monitored_item.Value.StatusCode
        if status is not None and not status.is_good():
            self.tally.error(f"session {self.k}: data change of {node}: {status.name}")

    def status_change_notification(self, status):
        code = getattr(status.Status, "name", status.Status)
        self.tally.error(f"session {self.k}: subscription status change: {code}")


async def asyncua_nodes(client):
    """Every variable under Inputs and Outputs, and every step's X."""
    ns = await client.get_namespace_index(NS_URI)
    wash = await client.nodes.objects.get_child([f"{ns}:CarWash"])
    nodes = []
    for section in ("Inputs", "Outputs"):
        nodes.extend(await (await wash.get_child([f"{ns}:{section}"])).get_children())
    for step in await (await wash.get_child([f"{ns}:Chart", f"{ns}:Steps"])).get_children():
        nodes.append(await step.get_child([f"{ns}:X"]))
    runtime = await wash.get_child([f"{ns}:Runtime"])
    reads = [await runtime.get_child([f"{ns}:State"]), await runtime.get_child([f"{ns}:ScanCount"])]
    return nodes, reads


async def asyncua_session(k, url, deadline, tally):
    """One session, subscribed until the deadline; made again after a failure."""
    from asyncua import Client

    left = lambda: deadline - time.monotonic()  # noqa: E731

    async def bounded(aw, limit):
        """`aw` within `limit` s, and not much past the deadline (0.5 s at least)."""
        return await asyncio.wait_for(aw, max(0.5, min(limit, left())))

    while left() > 0.5:
        client = Client(url=url, timeout=ASYNCUA_TIMEOUT)
        sub = None
        try:
            await bounded(client.connect(), 8)
            nodes, reads = await bounded(asyncua_nodes(client), 10)
            handler = AsyncuaHandler(k, tally)
            sub = await bounded(client.create_subscription(SUB_INTERVAL, handler), 5)
            results = await bounded(sub.subscribe_data_change(nodes, sampling_interval=SUB_INTERVAL), 10)
            bad = [r for r in results if not isinstance(r, int)]
            if bad:
                tally.error(f"session {k}: {len(bad)} of {len(nodes)} monitored items refused: {bad[0]}")
            tally.sessions.add(k)
            handler.last = time.monotonic()
            silent = False
            while left() > 0:
                await asyncio.sleep(min(READ_EVERY, max(left(), 0)))
                if left() <= 0:
                    break
                for node in reads:
                    tally.request()
                    dv = await bounded(node.read_data_value(raise_on_bad_status=False), ASYNCUA_TIMEOUT)
                    if not dv.StatusCode.is_good():
                        tally.error(f"session {k}: read {node}: {dv.StatusCode.name}")
                quiet = time.monotonic() - handler.last
                if quiet > SILENCE and not silent:
                    tally.error(f"session {k}: no data change for {quiet:.1f} s")
                silent = quiet > SILENCE
        except Exception as e:  # noqa: BLE001 - counted; the session is made again
            tally.error(f"session {k}: {short(e)}")
            await asyncio.sleep(min(1.0, max(left(), 0)))
        finally:
            # Close the session (deleting the subscription); a server that does not answer
            # within CLOSE_TIMEOUT gets its socket closed.
            try:
                if sub is not None:
                    await asyncio.wait_for(sub.delete(), CLOSE_TIMEOUT)
                await asyncio.wait_for(client.disconnect(), CLOSE_TIMEOUT)
            except Exception:  # noqa: BLE001 - the session may already be gone
                pass
            try:
                client.disconnect_socket()
            except Exception:  # noqa: BLE001
                pass


# --- (c) o6, in child processes --------------------------------------------------------------

O6_SESSIONS = 2
O6_LIFETIME = 240.0  # s: o6 ends its process after 10 minutes; replace each child every 4
O6_SETUP = 30.0  # s a new child gets to subscribe (importing o6 alone takes seconds of CPU)
O6_TIMEOUT = 2.0  # s, each request of the child
O6_CLOSE = 2.0  # s the child gives its disconnect
O6_STOP_GRACE = O6_TIMEOUT + O6_CLOSE + 2.0  # s a child gets to end once told to stop
# o6 noise on standard error that says nothing about the server.
O6_NOISE = ("SCRIPT MODE", "unknown Subscription", "Received BadNoSubscription")


def o6_child(url, seconds):
    """The child: one o6 session subscribed to the same nodes; stops at EOF on standard input
    or after `seconds` (+ a margin, should the parent be gone). A reporter thread prints the
    cumulative counts as a JSON line every second, whatever the session is blocked on, and
    once more at the end: {"requests", "notifications", "errors", "subscribed",
    "messages": [error messages new since the last line]}."""
    import o6

    stop = threading.Event()

    def watch_stdin():
        sys.stdin.read()  # returns at EOF: the parent closed the pipe (or died)
        stop.set()

    threading.Thread(target=watch_stdin, daemon=True).start()
    end = time.monotonic() + seconds + 30
    lock = threading.Lock()
    counts = {"requests": 0, "notifications": 0, "errors": 0, "subscribed": False}
    new_messages = []
    last_change = [time.monotonic()]

    def error(message):
        with lock:
            counts["errors"] += 1
            new_messages.append(message)

    def report():
        with lock:
            line = dict(counts, messages=list(new_messages))
            new_messages.clear()
        print(json.dumps(line), flush=True)

    # When the session began its setup (connect, browse, subscribe); None once subscribed.
    setup_since = [time.monotonic()]

    def reporter():
        blocked = False
        while not stop.wait(1.0):
            # A setup that neither ends nor fails (a connect that never returns) is an error.
            since = setup_since[0]
            if since is not None and time.monotonic() - since > SETUP_LIMIT:
                if not blocked:
                    error(f"session setup blocked for {SETUP_LIMIT:.0f} s")
                blocked = True
            else:
                blocked = False
            report()

    threading.Thread(target=reporter, daemon=True).start()

    def on_change(item, dv):  # on o6's worker thread
        last_change[0] = time.monotonic()
        with lock:
            counts["notifications"] += 1
        if o6.StatusCode.BAD in dv.status or o6.StatusCode.UNCERTAIN in dv.status:
            error(f"data change of {item.itemToMonitor.nodeId}: {dv.status.name}")

    nsu = f"nsu={NS_URI};s="
    state, scans = nsu + "CarWash/Runtime/State", nsu + "CarWash/Runtime/ScanCount"
    all_fields = o6.ns.ns0.datatypes.BrowseResultMask.ALL

    def close(client):
        """Disconnect (deletes the subscription, closes the session), within O6_CLOSE s."""
        closer = threading.Thread(target=client.disconnect, daemon=True)
        closer.start()
        closer.join(O6_CLOSE)

    def session():
        while not stop.is_set() and time.monotonic() < end:
            setup_since[0] = time.monotonic()
            client = o6.Client(url)
            client.config.timeout = int(O6_TIMEOUT * 1000)  # ms, every request
            try:
                client.connect(createDefaultSubscription=False)

                def kids(node):
                    return {r.browseName.name: r.nodeId for r in client.browse(node, resultMask=all_fields)}

                wash = kids("i=85")["CarWash"]
                sections = kids(wash)
                nodes = list(kids(sections["Inputs"]).values()) + list(kids(sections["Outputs"]).values())
                for step in kids(kids(sections["Chart"])["Steps"]).values():
                    nodes.append(kids(step)["X"])
                sub = client.createSubscription(publishingInterval=SUB_INTERVAL)
                client.monitor(nodes, on_change, samplingInterval=SUB_INTERVAL, valueOnly=False, subscription=sub)
                counts["subscribed"] = True
                setup_since[0] = None
                last_change[0] = time.monotonic()
                silent = False
                while not stop.wait(READ_EVERY) and time.monotonic() < end:
                    for node in (state, scans):
                        with lock:
                            counts["requests"] += 1
                        dv = client.read(node, valueOnly=False)
                        if dv.status != o6.StatusCode.GOOD:
                            error(f"read {node}: {dv.status.name}")
                    quiet = time.monotonic() - last_change[0]
                    if quiet > SILENCE and not silent:
                        error(f"no data change for {quiet:.1f} s")
                    silent = quiet > SILENCE
            except Exception as e:  # noqa: BLE001 - counted; the session is made again
                if not stop.is_set():
                    error(short(e))
                    stop.wait(1.0)
            finally:
                close(client)

    # The session runs on its own thread, so that a call blocked on a silent server cannot
    # hold up the stop: at EOF (or the end) it gets O6_TIMEOUT + O6_CLOSE s to wind down.
    worker = threading.Thread(target=session, daemon=True)
    worker.start()
    while not stop.wait(0.2) and time.monotonic() < end:
        pass
    stop.set()
    worker.join(O6_TIMEOUT + O6_CLOSE)
    report()
    sys.stdout.flush()
    # o6's native threads may still be winding down a dead connection: do not wait for them.
    os._exit(0)


class O6Child:
    """One `--o6-child` process: its counts, as its JSON lines report them."""

    def __init__(self, k):
        self.k = k
        self.proc = None
        self.counts = {"requests": 0, "notifications": 0, "errors": 0}
        self.subscribed = asyncio.Event()
        self.started = time.monotonic()
        self.readers = None

    async def spawn(self, url, tally):
        # The child stops itself `budget` (+30) s after its start should this process vanish;
        # normally it is told to stop (EOF on its standard input) well before.
        budget = O6_LIFETIME + O6_SETUP + 30
        self.proc = await asyncio.create_subprocess_exec(
            sys.executable,
            os.path.abspath(__file__),
            "--o6-child",
            url,
            f"{budget:.0f}",
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        self.readers = asyncio.gather(self.read_stdout(tally), self.read_stderr())

    async def read_stdout(self, tally):
        async for raw in self.proc.stdout:
            line = raw.decode(errors="replace").strip()
            if not line.startswith("{"):
                continue  # o6's banner
            try:
                msg = json.loads(line)
            except ValueError:
                continue
            for key in self.counts:
                self.counts[key] = msg.get(key, self.counts[key])
            if msg.get("subscribed"):
                tally.sessions.add(self.k)
                self.subscribed.set()
            for m in msg.get("messages", []):
                record("o6", f"session {self.k}: {m}")

    async def read_stderr(self):
        async for raw in self.proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            if line and not any(n in line for n in O6_NOISE):
                print(f"soak_client: o6[{self.k}]: {line}", file=sys.stderr, flush=True)

    async def ready(self, limit):
        """Wait until the child has subscribed, or has ended, or `limit` s."""
        waits = [asyncio.ensure_future(self.subscribed.wait()), asyncio.ensure_future(self.proc.wait())]
        await asyncio.wait(waits, timeout=limit, return_when=asyncio.FIRST_COMPLETED)
        for w in waits:
            w.cancel()
        return self.subscribed.is_set()

    async def stop(self):
        """Ask the child to stop (EOF), kill it after O6_STOP_GRACE s. Returns what went wrong,
        or None for an orderly end."""
        problem = None
        if self.proc.returncode is not None:
            problem = f"child exited early with status {self.proc.returncode}"
        else:
            self.proc.stdin.close()
            try:
                await asyncio.wait_for(asyncio.shield(self.proc.wait()), O6_STOP_GRACE)
                if self.proc.returncode != 0:
                    problem = f"child exited with status {self.proc.returncode}"
            except asyncio.TimeoutError:
                self.proc.kill()
                await self.proc.wait()
                problem = f"child did not stop within {O6_STOP_GRACE:.0f} s; killed"
        try:
            await asyncio.wait_for(self.readers, 2)
        except asyncio.TimeoutError:
            self.readers.cancel()
        return problem


class O6Slot:
    """Keeps one o6 session alive: a child process, replaced every O6_LIFETIME s by a new one
    that is started (and subscribed) before the old one is stopped, so the load never pauses."""

    def __init__(self, k, url, tally):
        self.k, self.url, self.tally = k, url, tally
        self.children = []  # the live ones
        self.done = {"requests": 0, "notifications": 0, "errors": 0}  # of those that ended

    def totals(self):
        return {key: self.done[key] + sum(c.counts[key] for c in self.children) for key in self.done}

    async def start_child(self, deadline=None):
        """A new child, once it has subscribed (O6_SETUP s at most, and not past `deadline`)."""
        child = O6Child(self.k)
        await child.spawn(self.url, self.tally)
        self.children.append(child)
        limit = O6_SETUP if deadline is None else max(min(O6_SETUP, deadline - time.monotonic()), 0.1)
        if not await child.ready(limit) and child.proc.returncode is None:
            if deadline is None or time.monotonic() < deadline:
                self.done["errors"] += 1
                record("o6", f"session {self.k}: not subscribed {limit:.0f} s after its start")
        return child

    async def end_child(self, child):
        problem = await child.stop()
        self.children.remove(child)
        for key in self.done:
            self.done[key] += child.counts[key]
        if problem:
            self.done["errors"] += 1
            record("o6", f"session {self.k}: {problem}")

    async def run(self, deadline):
        """From the first child's start (done before the clock starts) until the deadline."""
        left = lambda: deadline - time.monotonic()  # noqa: E731
        child = self.children[0]
        while True:
            # Replace it at O6_LIFETIME, unless the run ends before a new one could take over.
            replace_at = child.started + O6_LIFETIME
            if deadline - replace_at < O6_SETUP + 5:
                replace_at = deadline
            wait = min(left(), replace_at - time.monotonic())
            try:
                await asyncio.wait_for(asyncio.shield(child.proc.wait()), max(wait, 0))
            except asyncio.TimeoutError:
                pass
            if child.proc.returncode is not None:  # died: counted, and replaced
                await self.end_child(child)
                if left() <= 1.0:
                    return
                await asyncio.sleep(min(1.0, max(left(), 0)))
                child = await self.start_child(deadline)
                continue
            if left() <= 0:
                await self.end_child(child)
                return
            # A planned replacement: the new one first, then the old one goes.
            new = await self.start_child(deadline)
            self.tally.restarts += 1
            await self.end_child(child)
            child = new


# --- The run --------------------------------------------------------------------------------


def o6_totals(o6_tally, slots):
    """Fold the o6 children's counts into the o6 tally."""
    totals = [slot.totals() for slot in slots]
    with o6_tally.lock:
        o6_tally.requests = sum(t["requests"] for t in totals)
        o6_tally.notifications = sum(t["notifications"] for t in totals)
        o6_tally.errors = sum(t["errors"] for t in totals)


def summary(clock, modbus, ua, o6t):
    now = time.monotonic()
    started = clock.get("started", now)
    stopping = clock.get("stopping", now)
    return {
        "seconds": round(stopping - started, 1),
        "setup_seconds": round(started - clock["setup"], 1),
        "stop_seconds": round(now - stopping, 1),
        "modbus": {"requests": modbus.requests, "errors": modbus.errors, "pollers": MODBUS_POLLERS, "writer": 1},
        "asyncua": {
            "sessions": len(ua.sessions),
            "notifications": ua.notifications,
            "errors": ua.errors,
            "reads": ua.requests,
        },
        "o6": {
            "sessions": len(o6t.sessions),
            "notifications": o6t.notifications,
            "errors": o6t.errors,
            "restarts": o6t.restarts,
            "reads": o6t.requests,
        },
        "errors": list(_messages),
    }


async def soak(url, port, seconds, tallies, clock):
    modbus, ua, o6t, slots = tallies

    # Setup, before the clock starts: the o6 children (a few seconds of CPU to import o6 and
    # open62541 each) until they have subscribed, so that the load runs SECONDS with all
    # sessions up. Bounded by O6_SETUP; a child that fails is counted and replaced later.
    slots.extend(O6Slot(k, url, o6t) for k in range(O6_SESSIONS))
    await asyncio.gather(*(slot.start_child() for slot in slots))

    clock["started"] = time.monotonic()
    deadline = clock["started"] + seconds

    # (a) Modbus, on threads (the sync client, each call bounded by its timeout).
    stop = threading.Event()
    threads = [
        threading.Thread(target=modbus_poller, args=(k, port, stop, modbus), daemon=True) for k in range(MODBUS_POLLERS)
    ]
    threads.append(threading.Thread(target=modbus_writer, args=(port, stop, modbus), daemon=True))
    for t in threads:
        t.start()

    # (b) and (c) on the event loop.
    tasks = [asyncio.create_task(asyncua_session(k, url, deadline, ua)) for k in range(ASYNCUA_SESSIONS)]
    tasks += [asyncio.create_task(slot.run(deadline)) for slot in slots]

    async def progress():
        while True:
            await asyncio.sleep(10)
            o6_totals(o6t, slots)
            print(
                f"soak_client: {time.monotonic() - clock['started']:.0f} s: "
                f"modbus {modbus.requests} requests, {modbus.errors} errors; "
                f"asyncua {len(ua.sessions)} sessions, {ua.notifications} notifications, {ua.errors} errors; "
                f"o6 {len(o6t.sessions)} sessions, {o6t.notifications} notifications, {o6t.errors} errors, "
                f"{o6t.restarts} restarts",
                file=sys.stderr,
                flush=True,
            )

    ticker = asyncio.create_task(progress())
    await asyncio.sleep(max(deadline - time.monotonic(), 0))
    clock["stopping"] = time.monotonic()
    stop.set()
    # Every task ends by itself shortly after the deadline (bounded waits); cancel stragglers.
    done, pending = await asyncio.wait(tasks, timeout=O6_STOP_GRACE + 4)
    for t in pending:
        t.cancel()
        record("soak", f"task {t.get_coro().__qualname__} did not end in time; cancelled")
    await asyncio.gather(*pending, return_exceptions=True)
    for t in done:
        if t.exception() is not None:
            record("soak", f"task {t.get_coro().__qualname__}: {short(t.exception())}")
    for slot in slots:  # children left by a cancelled slot
        for child in list(slot.children):
            if child.proc.returncode is None:
                child.proc.kill()
    ticker.cancel()
    await asyncio.gather(ticker, return_exceptions=True)
    for t in threads:
        t.join(timeout=3)


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--o6-child":
        o6_child(sys.argv[2], float(sys.argv[3]))
        return
    if len(sys.argv) != 4:
        sys.exit("usage: soak_client.py OPCUA_URL MODBUS_PORT SECONDS")
    url, port, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    tallies = (Tally("modbus"), Tally("asyncua"), Tally("o6"), [])
    clock = {"setup": time.monotonic()}  # then "started" (the load), "stopping" (its end)

    def final_report():
        o6_totals(tallies[2], tallies[3])
        print(json.dumps(summary(clock, *tallies[:3])), flush=True)

    # A last resort: should the orderly stop itself hang, report anyway and leave.
    def hard_stop(*_):
        record("soak", "hard stop: the orderly stop did not finish")
        final_report()
        os._exit(1)

    signal.signal(signal.SIGALRM, hard_stop)
    signal.alarm(int(O6_SETUP + seconds + 40))
    try:
        asyncio.run(soak(url, port, seconds, tallies, clock))
    except Exception as e:  # noqa: BLE001 - report what was counted, then fail
        record("soak", short(e))
        final_report()
        sys.exit(f"soak_client.py: unexpected {short(e)}")
    signal.alarm(0)
    final_report()


if __name__ == "__main__":
    main()
