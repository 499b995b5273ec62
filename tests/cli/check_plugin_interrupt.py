"""Ctrl-C and SIGTERM end a read that blocks. The built-in readers take regular files only, but a
plugin's reader does its own I/O: here the example plugin's .occtxt reader opens a FIFO and
waits in read() for data that never comes. The command's signal handlers used SA_RESTART, so
the read was restarted after each signal and the command hung, ignoring both; now the read
fails with EINTR and the command exits 130 (143 for SIGTERM), leaving no output.
Arguments: the occseg tool, a work directory, the folder holding occseg_example.so.
The signal is sent again and again until the command exits: one sent just before the plugin
enters read() would only set the flag. The time limit is a guard: a hang fails the check."""
import errno
import os
import signal
import subprocess
import sys
import time

occseg, work, plugin_dir = sys.argv[1], sys.argv[2], sys.argv[3]
assert os.path.exists(os.path.join(plugin_dir, "occseg_example.so")), plugin_dir

for sig, code in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
    fifo = os.path.join(work, f"stuck-{sig}.occtxt")
    os.mkfifo(fifo)
    out = os.path.join(work, f"out-{sig}")
    p = subprocess.Popen([occseg, "segment", fifo, "--out", out], cwd=work, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env={**os.environ, "OCCSEG_PLUGIN_PATH": plugin_dir})
    writer, deadline = None, time.time() + 120
    while writer is None:  # a non-blocking open for writing succeeds once the reader has the FIFO open
        assert p.poll() is None, ("exited before reading", p.returncode, p.communicate())
        assert time.time() < deadline, "the plugin never opened the FIFO"
        try:
            writer = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
        except OSError as e:
            assert e.errno == errno.ENXIO, e
            time.sleep(0.05)
    try:  # the writer stays open and silent: the reader waits in read()
        while p.poll() is None:
            assert time.time() < deadline, f"signal {sig} did not end the blocked read"
            p.send_signal(sig)
            time.sleep(0.2)
        stdout, stderr = p.communicate()
    finally:
        if p.poll() is None:
            p.kill()
        os.close(writer)
    assert p.returncode == code, (sig, p.returncode, stderr)
    assert "stopped; no output file was changed" in stderr, stderr
    assert stdout == "" and not os.path.exists(out), (stdout, os.listdir(work))
print("cli plugin interrupt: all checks passed")
