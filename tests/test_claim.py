"""One process at a time per run folder (sweep/claim.py): the second is told at once, and a claim
dies with its holder."""

import subprocess
import sys
import time

from mediated_transfer.sweep.claim import CLAIM_FILE, claimed


def test_a_held_claim_is_refused_and_free_again_once_released(tmp_path):
    with claimed(tmp_path / "run") as first:
        assert first
        with claimed(tmp_path / "run") as second:
            assert not second
        with claimed(tmp_path / "other") as other:
            assert other
    with claimed(tmp_path / "run") as again:
        assert again


def test_a_claim_dies_with_its_process_even_on_sigkill(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time\n"
        "from mediated_transfer.sweep.claim import claimed\n"
        f"with claimed({str(tmp_path)!r}):\n"
        "    print('held', flush=True)\n"
        "    time.sleep(600)\n")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with claimed(tmp_path) as mine:
            assert not mine
    finally:
        holder.kill()
        holder.wait()
    deadline = time.time() + 10
    while True:
        with claimed(tmp_path) as mine:
            if mine:
                break
        assert time.time() < deadline, "the claim outlived its killed holder"
        time.sleep(0.1)
    assert (tmp_path / CLAIM_FILE).exists()


def test_a_claim_file_follows_the_umask_so_that_a_group_can_share_it(tmp_path):
    import os
    import stat

    for umask in (0o002, 0o022):
        previous = os.umask(umask)
        try:
            with claimed(tmp_path / oct(umask)) as mine:
                assert mine
        finally:
            os.umask(previous)
        assert stat.S_IMODE((tmp_path / oct(umask) / CLAIM_FILE).stat().st_mode) == 0o666 & ~umask


def test_a_held_claim_records_its_holder_and_a_free_one_nobody(tmp_path):
    import json
    import os
    import socket

    from mediated_transfer.sweep.claim import holder

    with claimed(tmp_path, {"sweep": "s", "config": {"a": 1}}) as mine:
        assert mine
        found = holder(tmp_path)
        assert found is not None and found["pid"] == os.getpid()
        assert found["record"] == {"sweep": "s", "config": {"a": 1}}
    assert holder(tmp_path, wait_s=0) is None  # emptied on release
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    # A holder killed before it could empty the file: its record is not taken for a live holder's.
    (tmp_path / CLAIM_FILE).write_text(json.dumps({"pid": gone.pid, "host": socket.gethostname(),
                                                   "record": {"config": {"a": 2}}}))
    assert holder(tmp_path, wait_s=0) is None
