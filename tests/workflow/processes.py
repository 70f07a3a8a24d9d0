"""Process-table helpers for the workflow tests that stop or kill scripts/experiment.py
(test_interrupt.py, test_resume.py): Linux /proc only."""
import fcntl
import os
import signal
import time


def process_state(pid):
    """(state letter, parent pid, process group) of a process from /proc/<pid>/stat, or None once
    it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError):
        return None
    return fields[0], int(fields[1]), int(fields[2])


def finished(pid, state):
    """A zombie has finished, unless only its first thread has: Snakemake's leader shows "Z"
    while its other threads still hold its files (the folder's lock among them)."""
    if state[0] != "Z":
        return False
    try:
        return len(os.listdir(f"/proc/{pid}/task")) <= 1
    except FileNotFoundError:
        return True


def alive(pid):
    """True while pid runs."""
    state = process_state(pid)
    return state is not None and not finished(pid, state)


def running_processes():
    """{pid: (state, parent, group)} of every process that has not finished."""
    states = {int(e): process_state(e) for e in os.listdir("/proc") if e.isdigit()}
    return {pid: st for pid, st in states.items() if st and not finished(pid, st)}


def group_members(pgid):
    """Running (not zombie) processes of process group pgid. kill(-pgid, 0) would count a
    zombie that init has not reaped yet."""
    return [pid for pid, st in running_processes().items() if st[2] == pgid]


def groups_below(pid):
    """Process groups of pid and of every running descendant of it."""
    procs = running_processes()
    tree = {pid}
    grew = True
    while grew:
        children = {c for c, st in procs.items() if st[1] in tree} - tree
        tree |= children
        grew = bool(children)
    return {procs[p][2] for p in tree if p in procs}


def kill_groups(groups):
    """SIGKILL to every process group in groups (those gone already are skipped)."""
    for g in groups:
        try:
            os.killpg(g, signal.SIGKILL)
        except ProcessLookupError:
            pass


def wait_until(condition, seconds):
    end = time.time() + seconds
    while time.time() < end:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def lock_is_free(out):
    """True when no experiment run holds the folder's lock (scripts/experiment.py)."""
    with open(os.path.join(out, ".experiment.lock"), "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
    return True


def gone_and_unlocked(groups, out):
    """True once no process of these groups runs and the folder's lock is free: a killed run
    has left nothing that could work beside the next one."""
    return not any(group_members(g) for g in groups) and lock_is_free(out)
