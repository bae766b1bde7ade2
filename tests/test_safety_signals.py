"""SIGINT/SIGTERM/SIGHUP: exit 128+signum, one line, old report or new one, no temporary folder."""

import os
import signal
import subprocess
import sys
import time

import pytest
from test_safety_report_output import (
    CHILD,
    MATERIAL,
    ROOT,
    _fake_run,
    _is_complete_report,
    _no_leftovers,
)

ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
@pytest.mark.parametrize("delay", [0.0, 0.3, 0.9])
def test_signal_during_report_leaves_old_or_new(tmp_path, signum, delay):
    out = tmp_path / "rep"
    assert _fake_run(out).returncode == 0
    old = (out / "report.json").read_bytes()
    p = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(MATERIAL), str(out), "0.6"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    try:
        assert p.stdout.readline().strip() == "started"
        time.sleep(delay)
        p.send_signal(signum)
        code = p.wait(timeout=60)
    finally:
        p.kill()
        p.stdout.close()
        p.stderr.close()
    # -signum: the signal arrived after the report was written, while Python was tearing the
    # interpreter down (it restores the default dispositions then): the new report stands
    assert code in (0, 128 + signum, -signum)
    assert _is_complete_report(out)
    if code == 128 + signum:
        assert (out / "report.json").read_bytes() == old
    assert _no_leftovers(tmp_path)


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_cli_signal_exit_status_one_line(tmp_path, signum):
    """Any command: a termination signal gives exit 128+signum and one line, no traceback."""
    script = (
        "import sys, time\nfrom openpbr_diffuse.cli import main as m\n"
        "def add_parser(sub):\n p = sub.add_parser('sleep'); p.set_defaults(run=run)\n"
        "def run(args):\n print('started', flush=True); time.sleep(30); return 0\n"
        "import types; mod = types.ModuleType('openpbr_diffuse.cli.sleep'); mod.add_parser = add_parser\n"
        "sys.modules[mod.__name__] = mod; m.COMMANDS['sleep'] = 'sleep'\n"
        "sys.exit(m.main(['sleep']))\n"
    )
    p = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, cwd=tmp_path
    )
    try:
        assert p.stdout.readline().strip() == "started"
        p.send_signal(signum)
        code = p.wait(timeout=60)
        err = p.stderr.read()
    finally:
        p.kill()
        p.stdout.close()
        p.stderr.close()
    assert code == 128 + signum
    assert len(err.strip().splitlines()) == 1 and "interrupted" in err and "Traceback" not in err


def test_signal_while_the_staging_folder_is_made_leaves_nothing(tmp_path, monkeypatch):
    """A signal that arrives just after the staging folder exists (here: sent by the folder's
    own creation) is delivered once the run owns the folder, which it then removes: no
    ``.NAME.tmp-*`` is left behind and the run ends with ``Terminated``."""
    import os

    from openpbr_diffuse import _signals
    from openpbr_diffuse.report import output
    from openpbr_diffuse.report.runner import run_report

    made = output.staging_dir

    def staging_dir_then_signal(out):
        tmp = made(out)
        os.kill(os.getpid(), signal.SIGTERM)
        return tmp

    monkeypatch.setattr(output, "staging_dir", staging_dir_then_signal)
    saved = {s: signal.getsignal(s) for s in _signals.SIGNALS}
    try:
        _signals.install()
        with pytest.raises(_signals.Terminated):
            run_report([str(MATERIAL)], tmp_path / "rep", progress=False, sections=["approximations"])
    finally:
        for s, h in saved.items():
            signal.signal(s, h)
    assert _no_leftovers(tmp_path)
    assert not (tmp_path / "rep").exists()


def test_a_signal_inside_a_held_step_is_raised_when_the_step_ends():
    """Inside ``_signals.blocked`` a signal raises nothing (the step runs to its end, even
    with worker threads alive that the kernel may hand it to); the block's end raises it as
    ``Terminated``, unless the block ends with an exception of its own."""
    import os
    import threading

    from openpbr_diffuse import _signals

    saved = {s: signal.getsignal(s) for s in _signals.SIGNALS}
    stop = threading.Event()
    worker = threading.Thread(target=stop.wait)  # a thread the kernel may deliver to
    worker.start()
    try:
        _signals.install()

        def signal_and_wait_for_the_handler(signum):
            seen = len(_signals._received)
            os.kill(os.getpid(), signum)
            deadline = time.monotonic() + 10.0
            while len(_signals._received) == seen and time.monotonic() < deadline:
                time.sleep(0.001)  # the handler runs here, inside the block
            return len(_signals._received) > seen

        with pytest.raises(_signals.Terminated) as caught:
            with _signals.blocked():
                handled = signal_and_wait_for_the_handler(signal.SIGTERM)
                finished = True  # reached: the handler raised nothing inside the block
        assert handled and finished and caught.value.signum == signal.SIGTERM
        with pytest.raises(RuntimeError):  # the step's own error wins
            with _signals.blocked():
                assert signal_and_wait_for_the_handler(signal.SIGHUP)
                raise RuntimeError("the step failed")
    finally:
        stop.set()
        worker.join()
        for s, h in saved.items():
            signal.signal(s, h)
