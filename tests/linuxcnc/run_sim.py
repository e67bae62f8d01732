#!/usr/bin/python3
"""Runs LinuxCNC's stock simulated mill headless with a plan of MDI moves and pin reads.

    run_sim.py --work DIR [--lib DIR_OF_libmtec_rt.so]

DIR holds case.json and plan.json (and the files they name); the results go to
DIR/results.json, LinuxCNC's output to DIR/linuxcnc.log. case.json:

    {"ini": [["JOINT_0", "COMP_FILE", "x.comp"], ["JOINT_0", "COMP_FILE_TYPE", "1"],
             ["MTEC", "MODEL", "{sim}/machine.json"]],
     "halfiles": ["mtec_eoffset.hal"], "files": ["x.comp", "mtec_eoffset.hal"],
     "component": true}

What it does, in order:
1. copies the stock simulation configuration of the Debian package
   (sample-configs/sim/axis/axis_mm.ini and its tool table) to DIR/sim;
2. makes it headless: DISPLAY = ./ui.py (tests/linuxcnc/ui.py), no axis_manualtoolchange.hal
   (it needs a Tk window) and no intro graphic; then sets the "ini" keys in their sections
   ({sim} in a value is the configuration folder) and
   appends the "halfiles" to [HAL]; copies the "files" beside the INI;
3. with "component": builds crates/mtec-rt/linuxcnc/mtec_eoffset.comp with halcompile against
   libmtec_rt.so (copied into DIR/sim, found through the module's rpath), copies
   mtec_eoffset.hal beside the INI, and puts the module in LinuxCNC's module directory for the
   run (rtapi_app loads modules only from there; needs root; a module already there is put
   back afterwards);
4. runs `linuxcnc -r axis_mm.ini` (-r: output to the terminal, as LinuxCNC's own tests do) as an
   ordinary user: LinuxCNC refuses to run as root, so as root it creates the user `mtecsim`
   (useradd) and runs as that user; otherwise as the calling user;
5. stops everything it started if the run takes longer than --timeout.

Exit codes: 0 the plan ran, 1 it failed (see results.json and linuxcnc.log), 77 LinuxCNC (or
halcompile, when the case needs it) is not installed.
"""

import argparse
import contextlib
import fcntl
import json
import os
import pwd
import shutil
import signal
import subprocess
import sys
import time

STOCK = "/usr/share/doc/linuxcnc/examples/sample-configs/sim"
HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
COMPONENT = os.path.join(REPO, "crates", "mtec-rt", "linuxcnc", "mtec_eoffset.comp")
COMPONENT_HAL = os.path.join(REPO, "crates", "mtec-rt", "linuxcnc", "mtec_eoffset.hal")
RTLIB_DIR = "/usr/lib/linuxcnc/modules"
USER = "mtecsim"
LOCK = "/tmp/mtec-linuxcnc-sim.lock"


def fail(msg, code=1):
    print("run_sim: " + msg, file=sys.stderr, flush=True)
    sys.exit(code)


def set_ini(lines, section, key, value):
    """Sets KEY = VALUE in [SECTION] (replacing the first KEY there, else adding it at the end
    of the section). LinuxCNC reads the first occurrence of a key in the first such section."""
    start = None
    for i, line in enumerate(lines):
        if line.strip() == "[%s]" % section:
            start = i
            break
    if start is None:
        lines.extend(["", "[%s]" % section, "%s = %s" % (key, value)])
        return
    end = len(lines)
    for i in range(start + 1, len(lines)):
        if lines[i].strip().startswith("["):
            end = i
            break
    for i in range(start + 1, end):
        if lines[i].split("=")[0].strip() == key:
            lines[i] = "%s = %s" % (key, value)
            return
    while end > start + 1 and lines[end - 1].strip() == "":
        end -= 1
    lines.insert(end, "%s = %s" % (key, value))


def add_halfile(lines, name):
    last = max(i for i, line in enumerate(lines) if line.split("=")[0].strip() == "HALFILE")
    lines.insert(last + 1, "HALFILE = %s" % name)


def headless_ini(text):
    out = []
    for line in text.splitlines():
        key = line.split("=")[0].strip()
        if key == "DISPLAY":
            line = "DISPLAY = ./ui.py"
        elif key in ("INTRO_GRAPHIC", "INTRO_TIME"):
            continue  # the splash screen needs a display
        elif key == "HALFILE" and "axis_manualtoolchange.hal" in line:
            continue  # a Tk dialog
        out.append(line)
    return out


def build_component(sim, lib_dir):
    """Builds mtec_eoffset.so in SIM against libmtec_rt.so (copied into SIM, found through the
    module's rpath) and returns its path."""
    if shutil.which("halcompile") is None:
        fail("halcompile not found (Debian package linuxcnc-uspace-dev)", 77)
    so = os.path.join(lib_dir, "libmtec_rt.so")
    if not os.path.exists(so):
        fail("%s not found" % so)
    shutil.copy(so, sim)
    env = dict(os.environ)
    env["LDFLAGS"] = "-L%s -Wl,-rpath,%s -Wl,--no-as-needed -lmtec_rt" % (sim, sim)
    t = time.monotonic()
    out = subprocess.run(
        ["halcompile", "--compile", COMPONENT], cwd=sim, env=env, capture_output=True, text=True
    )
    if out.returncode != 0:
        fail("halcompile failed:\n%s%s" % (out.stdout, out.stderr))
    print("run_sim: built mtec_eoffset.so in %.1f s" % (time.monotonic() - t), flush=True)
    shutil.copy(COMPONENT_HAL, sim)
    return os.path.join(sim, "mtec_eoffset.so")


class InstalledModule:
    """rtapi_app loads realtime modules only from its module directory (a module name with a
    slash is refused), so the test's build is copied there for the run; a module already there
    is put back afterwards."""

    def __init__(self, built):
        self.built = built
        self.dest = os.path.join(RTLIB_DIR, "mtec_eoffset.so")
        self.backup = None

    def __enter__(self):
        if not os.access(RTLIB_DIR, os.W_OK):
            fail("%s is not writable: run as root to install the test's module" % RTLIB_DIR, 77)
        if os.path.exists(self.dest):
            self.backup = self.dest + ".mtec-test-backup"
            shutil.move(self.dest, self.backup)
        shutil.copy(self.built, self.dest)
        os.chmod(self.dest, 0o644)
        return self

    def __exit__(self, *exc):
        os.remove(self.dest)
        if self.backup:
            shutil.move(self.backup, self.dest)
        return False


def ensure_user():
    try:
        pwd.getpwnam(USER)
    except KeyError:
        subprocess.run(["useradd", "--create-home", "--shell", "/bin/bash", USER], check=True)
    user = pwd.getpwnam(USER)
    # LinuxCNC writes its logs to HOME: a home left to another uid (two useradds that raced
    # before the lock covered them) is given back to the user
    if os.path.isdir(user.pw_dir) and os.stat(user.pw_dir).st_uid != user.pw_uid:
        chown_tree(user.pw_dir, user.pw_uid, user.pw_gid)
    return user


def chown_tree(path, uid, gid):
    for root, dirs, files in os.walk(path):
        os.chown(root, uid, gid)
        for name in files:
            os.chown(os.path.join(root, name), uid, gid)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    ap.add_argument("--lib", default=None)
    ap.add_argument("--timeout", type=float, default=150.0)
    args = ap.parse_args()

    if shutil.which("linuxcnc") is None or not os.path.isdir(STOCK):
        fail("LinuxCNC is not installed (Debian package linuxcnc-uspace)", 77)
    work = os.path.abspath(args.work)
    with open(os.path.join(work, "case.json")) as f:
        case = json.load(f)

    sim = os.path.join(work, "sim")
    os.makedirs(sim, exist_ok=True)
    with open(os.path.join(STOCK, "axis", "axis_mm.ini")) as f:
        lines = headless_ini(f.read())
    for section, key, value in case.get("ini", []):
        set_ini(lines, section, key, value.replace("{sim}", sim))
    for name in case.get("halfiles", []):
        add_halfile(lines, name)
    ini = os.path.join(sim, "axis_mm.ini")
    with open(ini, "w") as f:
        f.write("\n".join(lines) + "\n")
    shutil.copy(os.path.join(STOCK, "sim_mm.tbl"), sim)
    shutil.copy(os.path.join(HERE, "ui.py"), sim)
    os.chmod(os.path.join(sim, "ui.py"), 0o755)
    shutil.copy(os.path.join(work, "plan.json"), sim)
    for name in case.get("files", []):
        shutil.copy(os.path.join(work, name), sim)
    module = contextlib.nullcontext()
    if case.get("component"):
        if not args.lib:
            fail("--lib is needed to build the component")
        module = InstalledModule(build_component(sim, os.path.abspath(args.lib)))

    cmd = ["linuxcnc", "-r", "axis_mm.ini"]
    # one simulation at a time on this machine (HAL shared memory, NML channels and the module
    # directory are global); the user is created under the same lock, since tests that start
    # together on a fresh machine would otherwise run useradd twice and leave a broken account
    with open(LOCK, "w") as lock:
        try:
            os.chmod(LOCK, 0o666)
        except PermissionError:
            pass  # another user's lock file: it is already shared
        fcntl.flock(lock, fcntl.LOCK_EX)
        if os.geteuid() == 0:
            user = ensure_user()
            chown_tree(work, user.pw_uid, user.pw_gid)
            os.chmod(work, 0o755)
            cmd = ["runuser", "-u", USER, "--", "env", "HOME=" + user.pw_dir] + cmd
        with module:
            t = time.monotonic()
            with open(os.path.join(work, "linuxcnc.log"), "w") as logf:
                # no terminal and no X display: LinuxCNC then never asks anything (a leftover
                # instance is cleaned up without the "Restart it? [Y/n]" prompt)
                env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
                proc = subprocess.Popen(
                    cmd,
                    cwd=sim,
                    env=env,
                    stdin=subprocess.DEVNULL,
                    stdout=logf,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )
                try:
                    proc.wait(timeout=args.timeout)
                except subprocess.TimeoutExpired:
                    # LinuxCNC's script cleans up on TERM; whatever of ours is left in the group
                    # (the UI) is killed. A leftover server or rtapi_app, which start their own
                    # sessions, is cleaned up by the next `linuxcnc` start.
                    os.killpg(proc.pid, signal.SIGTERM)
                    try:
                        proc.wait(timeout=10)
                    except subprocess.TimeoutExpired:
                        pass
                    try:
                        os.killpg(proc.pid, signal.SIGKILL)
                    except ProcessLookupError:
                        pass
                    proc.wait()
                    fail("LinuxCNC did not finish within %.0f s (see %s/linuxcnc.log)" % (args.timeout, work))
            print("run_sim: LinuxCNC ran %.1f s" % (time.monotonic() - t), flush=True)

    results = os.path.join(sim, "results.json")
    if not os.path.exists(results):
        fail("no results.json: the UI did not run (see %s/linuxcnc.log)" % work)
    shutil.copy(results, os.path.join(work, "results.json"))
    with open(results) as f:
        if not json.load(f)["ok"]:
            fail("the plan failed (see %s/results.json and linuxcnc.log)" % work)


if __name__ == "__main__":
    main()
