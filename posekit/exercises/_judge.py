"""The key out of the answer's reach: a checker's expected answers live in one process, the student's code in another.

A checker (``posekit.exercises.check_fk(my_fk)``) used to build its cases, expected answers included, in the
process that runs the student's function: an answer that walked the call stack to the checker's frame could read
them, and one that rebound the comparison (``_check._allclose``) or the reference function could pass. Now:

* the **judge** is a process that holds the expected answers and compares; it runs the checker's own body
  (:func:`judged` keeps it as ``checker.__wrapped__``) with a :class:`Remote` in place of the student's function;
  it is not dumpable (no process of the same user may trace it or read its memory) and never runs student code;
* the **executor** runs the student's function, and only that: for each case the judge sends the inputs, the
  executor calls the function under the checker's watch (:class:`posekit.exercises._check._Watch`: the posekit
  function it is compared against must not be called) and sends back what it returned, the inputs as they are
  afterwards (an answer that changes them in place is refused by the judge), what it raised, and what the watch saw.

What crosses is data only (:mod:`posekit.exercises._wire`: JSON with NumPy arrays, never a pickle). In a lesson the
student's kernel is the executor and :func:`ask` asks a judge (``python -m posekit.exercises._judge --serve``,
started on the kernel's first check and kept for the next: one check after another, each begun by a ``check``
line naming the lesson's checker); under
``posekit course autograde`` the judge is started by the grader and starts the executor itself
(:func:`grade`: ``python -m posekit.exercises._judge --grade``), so the verdict the grade book keeps comes from a
process the answer never ran in. One such judge checks a whole lesson's submissions: it reads one job (a student's
answer to one exercise) a line and writes its verdict a line, each job's answer in a fresh executor of its own, so
that no answer runs where another student's, or another exercise's, does. The executors are forked from a template
process that ran the lesson's imports once (:class:`_Template`; a new interpreter should it fail): a fork starts in
a tenth of a second where an interpreter importing torch takes seconds.
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import importlib
import io
import json
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading

from . import _wire
from ._check import CURRENT, Forbidden, WatchOff, _Watch

__all__ = ["judged", "ask", "grade", "Remote", "run_case"]


def _qualified(f) -> str:
    module = getattr(f, "__module__", None) or "?"
    return f"{module}:{getattr(f, '__qualname__', getattr(f, '__name__', repr(f)))}"


def _resolve(name: str):
    module, _, path = name.partition(":")
    obj = importlib.import_module(module)
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def _same(a, b) -> bool:
    """``a`` equals ``b`` as inputs go (arrays elementwise, NaN equal to NaN; lists and tuples item by item)."""
    import numpy as np

    if hasattr(a, "detach") and hasattr(a, "numpy"):
        a = a.detach().cpu().numpy()
    if hasattr(b, "detach") and hasattr(b, "numpy"):
        b = b.detach().cpu().numpy()
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (int, float, np.number)) and isinstance(b, (int, float, np.number)):  # as the wire carries them
        return a == b or (a != a and b != b)
    if type(a) is type(b) and hasattr(a, "__dataclass_fields__"):  # a Skeleton: field by field
        return all(_same(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__)
    return type(a) is type(b) and a == b


def _named_error(name: str, message: str) -> Exception:
    """An exception whose type is called as the answer's was (the judge never has the answer's own class)."""
    safe = name if name.isidentifier() else "Exception"
    return type(safe, (Exception,), {})(message)


class Remote:
    """The student's function as the judge calls it: each call is a case sent to the executor (module docstring)."""

    def __init__(self, send, receive):
        self._send, self._receive = send, receive

    def __call__(self, *args):
        forbid = [_qualified(f) for f in CURRENT.forbid]
        forbid += [n for n in CURRENT.own if n not in forbid]
        self._send({"call": True, "args": _wire.encode(args), "forbid": forbid})
        reply = self._receive()
        if reply is None:
            raise _named_error("ProcessEnded", "the process running your function stopped (it called exit?)")
        after = _wire.decode(reply.get("args_after"))
        CURRENT.changed = next((k for k, (a, b) in enumerate(zip(args, after or ())) if not _same(a, b)), None)
        if reply.get("watch_off"):
            raise WatchOff()
        if reply.get("forbidden"):
            raise Forbidden(str(reply["forbidden"]))
        if reply.get("not_attempted"):
            raise NotImplementedError
        if reply.get("raised"):
            name, message = reply["raised"]
            raise _named_error(str(name), str(message))
        return _wire.decode(reply.get("got"))


# -- the executor's side --------------------------------------------------------------------------------------------

def run_case(fn, message: dict) -> dict:
    """Run the student's ``fn`` on the inputs of ``message`` (a judge's call) under the watch; the reply."""
    args = _wire.decode(message["args"])
    forbid = []
    for name in message.get("forbid", []):
        with contextlib.suppress(Exception):
            forbid.append(_resolve(name))
    watch = _Watch(forbid)
    reply: dict = {}
    try:
        with watch:
            got = fn(*args)
        reply["got"] = _wire.encode(got)
    except NotImplementedError:
        reply["not_attempted"] = True
    except Exception as e:  # noqa: BLE001 - a student's bug is the judge's to report
        reply["raised"] = [type(e).__name__, str(e)]
    reply["args_after"] = _wire.encode(args)
    # named first: the posekit function compared against (the list's head) before the checker module's own helpers
    order = [name.replace(":", ".") for name in message.get("forbid", [])]
    reply["forbidden"] = min(watch.called, key=lambda n: order.index(n) if n in order else len(order)) \
        if watch.called else None
    reply["watch_off"] = watch.turned_off
    return reply


_WARM: dict = {"proc": None, "err": None}
"""The judge this process asks (:func:`ask`), started on the first check and kept for the next ones."""
_WARM_LOCK = threading.Lock()


def _warm_judge():
    proc = _WARM["proc"]
    if proc is None or proc.poll() is not None:
        _drop_judge()
        env = dict(os.environ)
        env.setdefault("MPLBACKEND", "Agg")
        err = tempfile.TemporaryFile("w+")  # a file, not a pipe: what the judge says is never waited on
        # a session of its own: a kernel shutting down signals the children in its process group and waits until
        # none is left, and this one, never reaped meanwhile, kept every kernel's shutdown waiting 2.5 s; the judge
        # still ends with the kernel (its input closes)
        proc = subprocess.Popen([sys.executable, "-m", "posekit.exercises._judge", "--serve"],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True, env=env,
                                start_new_session=True)
        _WARM.update(proc=proc, err=err)
    return proc


def _drop_judge() -> str:
    """Stop the warm judge (if any); the last line it wrote to standard error."""
    proc, err = _WARM["proc"], _WARM["err"]
    _WARM.update(proc=None, err=None)
    said = ""
    if proc is not None:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        for f in (proc.stdin, proc.stdout):
            with contextlib.suppress(Exception):
                f.close()
    if err is not None:
        with contextlib.suppress(Exception):
            err.seek(0)
            lines = err.read().strip().splitlines()
            said = lines[-1] if lines else ""
            err.close()
    return said


def ask(module: str, checker: str, fn) -> bool:
    """A lesson's check: ask this process's judge (``python -m posekit.exercises._judge --serve``, started on the
    first check and kept) for ``module.checker``, run each case it sends on ``fn`` here, print its verdict; True when
    it says every case passed. A check that does not end with a verdict (an error, an interrupted cell) stops that
    judge; the next check starts another."""
    with _WARM_LOCK:
        done = False
        try:
            proc = _warm_judge()
            try:
                proc.stdin.write(_wire.dumps({"check": [module, checker]}))
                proc.stdin.flush()
            except OSError:
                pass
            for line in proc.stdout:
                message = _wire.loads(line)
                if "verdict" in message:
                    print(message["verdict"], end="")
                    done = True
                    return message.get("passed") is True
                proc.stdin.write(_wire.dumps(run_case(fn, message)))
                proc.stdin.flush()
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=10)
            said = _drop_judge()
            print(f"✗ {checker}: the checker stopped before its verdict ({said or 'no message'})")
            return False
        finally:
            if not done:
                _drop_judge()


atexit.register(_drop_judge)


def judged(checker):
    """Make ``checker`` (a ``check_...(fn)`` whose body builds its cases and calls ``report``) run its body in a
    judge of its own; the body stays reachable as ``checker.__wrapped__`` (the judge calls that)."""
    @functools.wraps(checker)
    def check(fn) -> bool:
        return ask(checker.__module__, checker.__name__, fn)
    return check


# -- the judge --------------------------------------------------------------------------------------------------------

def _not_dumpable() -> None:
    """No process of this user may trace the judge or read its memory (Linux; elsewhere nothing is done)."""
    with contextlib.suppress(Exception):
        import ctypes

        ctypes.CDLL(None).prctl(4, 0, 0, 0, 0)  # PR_SET_DUMPABLE, 0


def _own_helpers(module: str) -> tuple:
    """``"module:name"`` of every function ``module`` (a lesson's checkers) defines besides its checkers: its
    references and the variants its messages compare with, several of which give the right answer with their
    defaults. An answer may call none of them (its executor forbids them as it forbids the posekit function)."""
    import types

    mod = importlib.import_module(module)
    return tuple(f"{module}:{name}" for name, f in vars(mod).items()
                 if isinstance(f, types.FunctionType) and f.__module__ == module and not name.startswith("check_"))


def _judge(module: str, checker: str, send, receive) -> tuple[bool, str]:
    """Run ``module.checker``'s body on a :class:`Remote`: (passed, what it printed)."""
    CURRENT.in_judge = True
    CURRENT.own = _own_helpers(module)
    body = getattr(importlib.import_module(module), checker)
    body = getattr(body, "__wrapped__", body)
    said = io.StringIO()
    with contextlib.redirect_stdout(said):
        try:
            passed = body(Remote(send, receive)) is True
        except Exception as e:  # noqa: BLE001 - the verdict says what stopped it
            print(f"✗ {checker}: {type(e).__name__}: {e}")
            passed = False
    return passed, said.getvalue()


def _lines(stream):
    def receive():
        line = stream.readline()
        return _wire.loads(line) if line else None
    return receive


def _writer(stream):
    def send(message):
        stream.write(_wire.dumps(message))
        stream.flush()
    return send


class _Spawned:
    """An answer's executor started as a new interpreter (``python -m posekit.exercises._judge --execute``): the
    lesson's imports run in it before the answer."""

    def __init__(self, env):
        self.proc = subprocess.Popen([sys.executable, "-m", "posekit.exercises._judge", "--execute"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     env=env, start_new_session=True)
        self.send, self.receive = _writer(self.proc.stdin), _lines(self.proc.stdout)
        self._printed = _drain(self.proc.stderr)

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            os.killpg(self.proc.pid, 9)  # the answer's process and whatever it started

    def close(self) -> str:
        """End the answer's input, wait for it (10 s, then kill it and what it started); what it printed."""
        with contextlib.suppress(Exception):
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.kill()
            self.proc.wait()
        printed = self._printed(10) or ""  # what it started may hold its standard error open: not waited for
        with contextlib.suppress(Exception):
            self.proc.stdout.close()
        return printed


class _Forked:
    """An answer's executor forked from a :class:`_Template` whose lesson imports have run: a process of its own,
    in a session of its own, that starts in a fraction of the time a new interpreter and the imports take."""

    def __init__(self, template: "_Template"):
        ours, theirs = socket.socketpair()
        r, w = os.pipe()
        try:
            template.ask([theirs.fileno(), w])
            self.pid = int(template.reply()["pid"])
        finally:
            theirs.close()
            os.close(w)
        self.sock = ours
        self.send = _writer(ours.makefile("w", encoding="utf-8"))
        self.receive = _lines(ours.makefile("r", encoding="utf-8"))
        self._printed = _drain(os.fdopen(r, encoding="utf-8", errors="replace"))

    def kill(self) -> None:
        for kill in (os.killpg, os.kill):  # its session, or itself if it has not made one yet
            with contextlib.suppress(OSError):
                kill(self.pid, 9)

    def close(self) -> str:
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_WR)  # the answer's input ends: the executor returns
        printed = self._printed(10)  # its standard error closes when it (and what it started) ends
        if printed is None:
            self.kill()
            printed = self._printed(10) or ""
        with contextlib.suppress(OSError):
            self.sock.close()
        return printed


def _drain(stream):
    """Read ``stream`` to its end in a thread (an answer that prints a lot never blocks); ``wait(timeout)`` gives the
    text, or None when it has not ended by then."""
    chunks: list[str] = []
    done = threading.Event()

    def pump():
        with contextlib.suppress(Exception):
            for chunk in iter(lambda: stream.read(65536), ""):
                chunks.append(chunk)
        with contextlib.suppress(Exception):
            stream.close()
        done.set()

    threading.Thread(target=pump, daemon=True).start()

    def wait(timeout: float):
        return "".join(chunks) if done.wait(timeout) else None
    return wait


class _Template:
    """A process that ran a lesson's imports once and forks a fresh executor for each answer
    (``python -m posekit.exercises._judge --template FD``). It never sees an answer nor an expected one: it receives
    the two ends an executor will use (a socket for the protocol, a pipe for what the answer prints) and replies with
    the executor's process id. It is not dumpable, so an answer cannot trace it and change the next forks; should an
    answer stop or kill it, the next answers are spawned as new interpreters instead (:class:`_Spawned`)."""

    def __init__(self, imports: str, env, timeout_s: float = 120):
        self.imports = imports
        self.ctl, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.proc = subprocess.Popen([sys.executable, "-m", "posekit.exercises._judge", "--template",
                                      str(theirs.fileno())], pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                                     start_new_session=True)
        theirs.close()
        self.ctl.settimeout(timeout_s)
        self.ctl.send(json.dumps({"imports": imports}).encode())
        self.ok = self.reply().get("ready") is True
        self.ctl.settimeout(10)

    def ask(self, fds) -> None:
        socket.send_fds(self.ctl, [b"fork"], fds)

    def reply(self) -> dict:
        data = self.ctl.recv(4096)
        if not data:
            raise OSError("the template process has ended")
        return json.loads(data)

    def stop(self) -> None:
        with contextlib.suppress(OSError):
            self.ctl.close()
        with contextlib.suppress(OSError):
            os.killpg(self.proc.pid, 9)
        with contextlib.suppress(Exception):
            self.proc.wait(timeout=10)


_TEMPLATES: list = []
"""The ``--grade`` judge's template process (:func:`grade` with ``fork``), started on its first job with that job's
lesson imports; stopped when the judge ends."""


def _executor(job: dict, env, fork: bool):
    """A fresh executor for ``job``'s answer: forked from the judge's template when ``fork`` (started on the first
    such job), else (or should the template fail) a new interpreter. A forked executor runs its own job's imports
    again before the answer: the template's are already loaded, a later exercise's extra ones load there."""
    if fork:
        template = _TEMPLATES[0] if _TEMPLATES else None
        try:
            if template is None:
                template = _Template(job.get("imports", ""), env)
                _TEMPLATES.append(template)
            if template.ok:
                return _Forked(template)
        except Exception:  # noqa: BLE001 - a stopped or killed template: this answer and the next are spawned
            if template is not None:
                template.ok = False
    return _Spawned(env)


@atexit.register
def _stop_templates() -> None:
    for template in _TEMPLATES:
        template.stop()
    _TEMPLATES.clear()


def grade(job: dict, timeout_s: float | None = None, fork: bool = False) -> dict:
    """The fresh check of one exercise (``posekit course autograde``): the judge in this process, the answer in a
    child executor that defines ``job["function"]`` from ``job["imports"]`` and ``job["source"]`` and runs the cases.
    Returns ``{"passed", "said"}``.

    The child is a process of its own in a session of its own, and is stopped with everything it started after
    ``timeout_s`` seconds (default ``job["timeout_s"]``, else 300): an endless loop fails the check, and the judge
    goes on to its next job. With ``fork`` (the ``--grade`` judge, which checks a lesson's answers one after another)
    it is forked from a template process that ran the lesson's imports once, else it is a new interpreter
    (``python -m posekit.exercises._judge --execute``); either way no other answer has run in it.
    """
    if timeout_s is None:
        timeout_s = float(job.get("timeout_s", 300))
    env = {k: v for k, v in os.environ.items() if not k.startswith("JPY_")}
    env.setdefault("MPLBACKEND", "Agg")
    child = _executor(job, env, fork)
    stopped = threading.Event()

    def stop():
        stopped.set()
        child.kill()

    timer = threading.Timer(timeout_s, stop)
    timer.daemon = True
    timer.start()
    try:
        try:
            child.send({"define": {k: job[k] for k in ("imports", "source", "function")}})
        except OSError:  # the child is gone already; the checker's first case says so
            pass
        passed, said = _judge(f"posekit.exercises.nb{job['lesson']}", job["checker"], child.send, child.receive)
    finally:
        timer.cancel()
        printed = child.close()
    if stopped.is_set():
        return {"passed": False, "said": f"the fresh check ran past {timeout_s:g} s and was stopped"}
    return {"passed": passed, "said": (printed.strip() + "\n" + said).strip()}


def _answer_loop(define: dict, namespace: dict, receive, send, imports_error=None) -> None:
    """Define the student's function in ``namespace`` (where the lesson's imports have run) on the first case, then
    run each case the judge sends (:func:`run_case`) until its input ends."""
    state: dict = {} if imports_error is None else {"imports": imports_error}

    def answer(*args):
        if "imports" in state:
            raise state["imports"]
        if "fn" not in state:
            code = compile("\n" * (define["imports"].count("\n") + 1) + define["source"], "<answer cell>", "exec")
            exec(code, namespace)  # noqa: S102 - the student's answer, in this throw-away process
            state["fn"] = namespace[define["function"]]
        return state["fn"](*args)

    while (message := receive()) is not None:
        send(run_case(answer, message))


def _run_imports(imports: str, namespace: dict):
    """The lesson's imports (its read-only cells') in ``namespace``, outside the watch, as the kernel ran them before
    the answer: importing torch makes code objects (asyncio's coroutines), which under the watch would read as
    switching it off. Returns the error they raised, or None."""
    try:
        exec(compile(imports, "<lesson imports>", "exec"), namespace)  # noqa: S102 - the lesson's own
    except Exception as e:  # noqa: BLE001 - said at the first case, as the answer's own error would be
        return e
    return None


def _execute() -> int:
    """The executor of :func:`grade` as a new interpreter: define the student's function (from the first line),
    then run each case.

    The protocol keeps the process's original standard output; the answer's own prints go to standard error."""
    protocol = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    receive, send = _lines(sys.stdin), _writer(protocol)
    define = (receive() or {}).get("define")
    if not define:
        return 2
    namespace = {"__name__": "__answer__"}
    _answer_loop(define, namespace, receive, send, _run_imports(define["imports"], namespace))
    return 0


def _template(fd: int) -> int:
    """The template of :class:`_Template`: run the lesson's imports, then fork an executor for each request."""
    _not_dumpable()
    ctl = socket.socket(fileno=fd)
    signal.signal(signal.SIGCHLD, signal.SIG_IGN)  # the executors are reaped as they end
    imports = json.loads(ctl.recv(1 << 20) or b"{}").get("imports", "")
    namespace = {"__name__": "__answer__"}
    if _run_imports(imports, namespace) is not None:
        ctl.send(json.dumps({"ready": False}).encode())  # the judge spawns each answer instead: it says the error
        return 1
    ctl.send(json.dumps({"ready": True}).encode())
    while True:
        try:
            data, fds, _, _ = socket.recv_fds(ctl, 64, 2)
        except OSError:
            return 0
        if not data:
            return 0
        if len(fds) != 2:
            for f in fds:
                os.close(f)
            return 2
        pid = os.fork()
        if pid == 0:  # the executor: a session of its own, the protocol on the socket, prints to the pipe
            code = 0
            try:
                ctl.close()
                os.setsid()
                signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                os.dup2(fds[1], 1)
                os.dup2(fds[1], 2)
                os.close(fds[1])
                null = os.open(os.devnull, os.O_RDONLY)
                os.dup2(null, 0)
                os.close(null)
                sys.stdout = sys.stderr = io.TextIOWrapper(os.fdopen(2, "wb", buffering=0), write_through=True)
                sock = socket.socket(fileno=fds[0])
                receive = _lines(sock.makefile("r", encoding="utf-8"))
                send = _writer(sock.makefile("w", encoding="utf-8"))
                define = (receive() or {}).get("define")
                if define:  # this job's imports: the template's ran already (cached), a later exercise's are added
                    _answer_loop(define, namespace, receive, send, _run_imports(define["imports"], namespace))
                else:
                    code = 2
            except BaseException:  # noqa: BLE001 - an executor never returns into the template's loop
                code = 1
            finally:
                with contextlib.suppress(Exception):
                    sys.stderr.flush()
                os._exit(code)
        for f in fds:
            os.close(f)
        ctl.send(json.dumps({"pid": pid}).encode())


def main(argv) -> int:
    if argv[1:2] == ["--execute"]:
        return _execute()
    if argv[1:2] == ["--template"] and len(argv) == 3 and argv[2].isdigit():
        return _template(int(argv[2]))
    _not_dumpable()
    if argv[1:2] == ["--grade"]:  # one job a line, one verdict a line, in order, until the input ends
        protocol = sys.stdout
        sys.stdout = sys.stderr  # nothing but the verdicts on the real standard output
        try:
            for line in sys.stdin:
                if line.strip():
                    protocol.write(json.dumps(grade(json.loads(line), fork=True)) + "\n")
                    protocol.flush()
        finally:
            _stop_templates()
        return 0
    if argv[1:2] == ["--serve"]:  # a kernel's judge (ask): one check after another, until the input ends
        receive = _lines(sys.stdin)
        send = _writer(sys.stdout)
        sys.stdout = sys.stderr  # nothing but the protocol on the real standard output
        while (message := receive()) is not None:
            module, checker = (list(message.get("check") or []) + ["", ""])[:2]
            if not (re.fullmatch(r"posekit\.exercises\.nb\d\d", str(module))
                    and re.fullmatch(r"check_\w+", str(checker))):
                print(f"not a lesson's checker: {module}.{checker}", file=sys.stderr)
                return 2
            passed, said = _judge(module, checker, send, receive)
            send({"verdict": said, "passed": passed})
        return 0
    print("usage: python -m posekit.exercises._judge --serve | --grade | --execute | --template FD", file=sys.stderr)
    return 2

if __name__ == "__main__":
    sys.exit(main(sys.argv))
