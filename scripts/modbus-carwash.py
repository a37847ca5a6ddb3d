#!/usr/bin/env python3
"""Plays the car wash machine against `sfc run examples/carwash/carwash.st --modbus HOST:PORT`
with a real Modbus TCP client (pymodbus), through two full cycles: with drying
(Idle -> Spraying -> Brushing -> Drying -> Idle) and without (... -> Brushing -> Returning -> Idle).

Inputs %IX0.b are written as coils 32768+b (Modbus cannot write discrete inputs), read back as
discrete inputs b; outputs %QX0.b are read as coils b (docs/runtime.md, "Modbus map").
Exit status 0 when every expectation held, 1 with the failed expectation otherwise.

usage: modbus-carwash.py HOST PORT
"""
import sys
import time

from pymodbus.client import ModbusTcpClient

INPUT_WINDOW = 32768
IN = {"StartButton": 0, "CarAtBrush": 1, "CarLeft": 2, "StopButton": 3, "CarPresent": 4, "AtHome": 5, "DryerSelect": 6}
OUT = ["SprayValve", "Travel", "Brush", "TravelBack", "Blower", "FaultLamp"]


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def main():
    host, port = sys.argv[1], int(sys.argv[2])
    c = ModbusTcpClient(host, port=port, timeout=3)
    if not c.connect():
        fail(f"cannot connect to {host}:{port}")

    def write(**inputs):
        for name, v in inputs.items():
            r = c.write_coil(INPUT_WINDOW + IN[name], bool(v))
            if r.isError():
                fail(f"writing {name}: {r}")
        r = c.read_discrete_inputs(0, count=7)
        if r.isError():
            fail(f"reading the inputs back: {r}")
        for name, v in inputs.items():
            if r.bits[IN[name]] != bool(v):
                fail(f"discrete input {IN[name]} ({name}) reads {r.bits[IN[name]]}, wrote {v}")

    def outputs():
        r = c.read_coils(0, count=len(OUT))
        if r.isError():
            fail(f"reading the outputs: {r}")
        return {name: r.bits[i] for i, name in enumerate(OUT)}

    def expect(what, timeout=6.0, **want):
        deadline = time.monotonic() + timeout
        while True:
            got = outputs()
            if all(got[k] == v for k, v in want.items()):
                print(f"ok: {what}: {want}")
                return
            if time.monotonic() > deadline:
                fail(f"{what}: expected {want}, outputs are {got}")
            time.sleep(0.02)

    off = {name: False for name in OUT}
    # Writing an output is refused: the chart owns it.
    r = c.write_coil(0, True)
    if not r.isError():
        fail("writing the output coil 0 was accepted")

    write(CarPresent=1, AtHome=1, DryerSelect=1, StartButton=0, CarAtBrush=0, CarLeft=0, StopButton=0)
    expect("idle", **off)
    # Wash 1, with drying.
    write(StartButton=1)
    expect("spraying", SprayValve=True, Travel=True, Brush=False)
    write(StartButton=0, AtHome=0)
    write(CarAtBrush=1)
    expect("brushing", SprayValve=True, Travel=True, Brush=True)
    write(CarAtBrush=0)
    write(CarLeft=1)
    expect("drying", SprayValve=False, Travel=False, Brush=False, Blower=True)
    write(CarLeft=0)
    # TravelBack is D BlowerSpinUp (T#3s) in Drying.
    expect("drying, gantry travels back after the spin-up", timeout=8.0, Blower=True, TravelBack=True)
    write(AtHome=1)
    expect("back to idle after drying", **off)
    # Wash 2, without drying.
    write(DryerSelect=0, StartButton=1)
    expect("spraying again", SprayValve=True, Travel=True)
    write(StartButton=0, AtHome=0, CarAtBrush=1)
    expect("brushing again", Brush=True)
    write(CarAtBrush=0, CarLeft=1)
    expect("returning", TravelBack=True, Blower=False, Brush=False, SprayValve=False)
    write(CarLeft=0, AtHome=1)
    expect("back to idle after returning", **off)
    c.close()
    print("car wash: two full cycles over Modbus TCP")


if __name__ == "__main__":
    main()
