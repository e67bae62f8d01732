#!/usr/bin/python3
"""Headless LinuxCNC user interface of mtec's simulation test (the INI's [DISPLAY]DISPLAY).

LinuxCNC starts it as `ui.py -ini FILE` once the HAL files are loaded. It takes the machine out
of E-stop, turns it on, homes all joints, switches to MDI and then runs plan.json (beside the
INI) step by step:

  {"op": "setp", "pin": "mtec.temp-00", "value": "25.1"} halcmd setp (a pin or parameter)
  {"op": "mdi", "code": "G53 G0 X10"}                    one MDI line, waits until it is done
  {"op": "machine", "value": "off"}                      machine off (or "on")
  {"op": "program", "file": "p.ngc"}                     runs a program (beside the INI) in
                                                         AUTO mode to its end, then back to MDI
  {"op": "read", "label": "x10", "pins": [...]}          waits until the pins are steady, reads
                                                         ("steady": false: reads at once)

Pins are read with the `hal` module (full double precision) and, for the record, with
`halcmd getp` (which prints 7 significant digits). Everything goes to results.json beside the
INI; LinuxCNC shuts down when this script exits. The pattern follows LinuxCNC's own test UIs
(tests/*/test-ui.py: linuxcnc.command / stat / error_channel, wait_complete).
"""

import json
import os
import subprocess
import sys
import time
import traceback

import hal
import linuxcnc

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
T0 = time.monotonic()


def log(msg):
    print("ui %.2f s: %s" % (time.monotonic() - T0, msg), flush=True)


def wait_for(what, predicate, timeout_s):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return
        time.sleep(0.02)
    raise RuntimeError("timed out after %.0f s waiting for %s" % (timeout_s, what))


class Ui:
    def __init__(self):
        # a HAL component of our own: the `hal` module reads pins only from a component
        self.comp = hal.component("mtec-ui")
        self.comp.ready()
        self.c = linuxcnc.command()
        self.s = linuxcnc.stat()
        self.e = linuxcnc.error_channel()

    def poll(self):
        self.s.poll()
        return self.s

    def check_errors(self, context):
        err = self.e.poll()
        if err:
            kind, text = err
            if kind in (linuxcnc.NML_ERROR, linuxcnc.OPERATOR_ERROR):
                raise RuntimeError("LinuxCNC error after %s: %s" % (context, text))
            log("message after %s: %s" % (context, text))

    def start(self):
        wait_for(
            "LinuxCNC to start",
            lambda: self.poll().task_state == linuxcnc.STATE_ESTOP
            and self.s.interp_state == linuxcnc.INTERP_IDLE
            and self.s.linear_units > 0,
            30,
        )
        self.c.state(linuxcnc.STATE_ESTOP_RESET)
        self.c.wait_complete()
        self.c.state(linuxcnc.STATE_ON)
        self.c.wait_complete()
        wait_for("machine on", lambda: self.poll().task_state == linuxcnc.STATE_ON, 10)
        self.c.mode(linuxcnc.MODE_MANUAL)
        self.c.wait_complete()
        self.c.home(-1)
        self.c.wait_complete()
        wait_for("homing", lambda: all(self.poll().homed[: self.s.joints]), 60)
        self.c.mode(linuxcnc.MODE_MDI)
        self.c.wait_complete()
        wait_for("MDI mode", lambda: self.poll().task_mode == linuxcnc.MODE_MDI, 10)
        self.check_errors("homing")
        log("on, homed, MDI")

    def machine(self, value):
        """Turns the machine off or on (LinuxCNC zeroes the external offsets at machine-on)."""
        on = {"off": False, "on": True}[value]
        self.c.state(linuxcnc.STATE_ON if on else linuxcnc.STATE_OFF)
        self.c.wait_complete()
        # machine off reads back as task_state STATE_ESTOP_RESET: test `enabled` instead
        wait_for("machine %s" % value, lambda: bool(self.poll().enabled) == on, 10)
        if value == "on":
            self.c.mode(linuxcnc.MODE_MDI)
            self.c.wait_complete()
        self.check_errors("machine " + value)

    def mdi(self, code):
        self.c.mdi(code)
        if self.c.wait_complete(60) == -1:
            raise RuntimeError("MDI `%s` did not complete" % code)
        wait_for(
            "`%s` to finish" % code,
            lambda: self.poll().interp_state == linuxcnc.INTERP_IDLE and self.s.inpos,
            60,
        )
        self.check_errors(code)

    def program(self, name):
        """Runs a whole program as the operator's Cycle Start would: the interpreter reads ahead
        as in production, unlike MDI, which synchronises after every line."""
        self.c.mode(linuxcnc.MODE_AUTO)
        self.c.wait_complete()
        self.c.program_open(os.path.join(HERE, name))
        self.c.wait_complete()
        self.c.auto(linuxcnc.AUTO_RUN, 0)
        self.c.wait_complete()
        # a short program can be over before the first poll: wait for it to start, or 2 s
        try:
            wait_for("start", lambda: self.poll().interp_state != linuxcnc.INTERP_IDLE, 2)
        except RuntimeError:
            pass
        wait_for(
            "`%s` to finish" % name,
            lambda: self.poll().interp_state == linuxcnc.INTERP_IDLE and self.s.inpos,
            120,
        )
        self.check_errors(name)
        self.c.mode(linuxcnc.MODE_MDI)
        self.c.wait_complete()

    def halcmd(self, *args):
        out = subprocess.run(["halcmd", *args], capture_output=True, text=True, timeout=20)
        if out.returncode != 0:
            raise RuntimeError("halcmd %s: %s" % (" ".join(args), out.stderr.strip()))
        return out.stdout.strip()

    def steady(self, pins, samples=40, interval_s=0.002, timeout_s=20):
        """Waits until no pin changes over `samples` consecutive polls (40 servo periods of
        1 ms or more): the external offset planner and the compensation filters have settled."""
        last, same = None, 0
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            now = [hal.get_value(p) for p in pins]
            if now == last:
                same += 1
                if same >= samples:
                    return now
            else:
                same = 0
            last = now
            time.sleep(interval_s)
        raise RuntimeError("pins %s did not settle: %s" % (pins, last))

    def read(self, label, pins, steady=True):
        values = self.steady(pins) if steady else [hal.get_value(p) for p in pins]
        texts = [self.halcmd("getp", p) for p in pins]
        # the values again: the pins must not have moved while halcmd ran
        again = [hal.get_value(p) for p in pins]
        if steady and again != values:
            raise RuntimeError("pins moved while reading %s: %s -> %s" % (label, values, again))
        self.poll()
        return {
            "label": label,
            "values": dict(zip(pins, values)),
            "halcmd": dict(zip(pins, texts)),
            "position": list(self.s.position[:3]),
            "tool_offset": list(self.s.tool_offset[:3]),
            "tool_in_spindle": self.s.tool_in_spindle,
        }


def main():
    result = {"ok": False, "steps": [], "error": None}
    out_path = os.path.join(HERE, "results.json")
    try:
        with open(os.path.join(HERE, "plan.json")) as f:
            plan = json.load(f)
        ui = Ui()
        ui.start()
        result["homed_s"] = time.monotonic() - T0
        for step in plan:
            op = step["op"]
            if op == "setp":
                ui.halcmd("setp", step["pin"], str(step["value"]))
            elif op == "machine":
                ui.machine(step["value"])
            elif op == "mdi":
                ui.mdi(step["code"])
            elif op == "program":
                ui.program(step["file"])
            elif op == "read":
                result["steps"].append(
                    ui.read(step["label"], step["pins"], step.get("steady", True))
                )
            else:
                raise RuntimeError("unknown plan step %r" % step)
        result["ok"] = True
    except Exception:
        result["error"] = traceback.format_exc()
        log(result["error"])
    result["elapsed_s"] = time.monotonic() - T0
    tmp = out_path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, out_path)
    log("done, ok=%s" % result["ok"])


if __name__ == "__main__":
    main()
