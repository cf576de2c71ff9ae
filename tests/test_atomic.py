"""Files written whole (atomic.py) are as readable as any file the user creates."""

import os
import stat

from mediated_transfer.atomic import atomic_write_text


def test_written_files_follow_the_umask_not_mkstemps_private_mode(tmp_path):
    path = atomic_write_text(tmp_path / "result.json", "{}\n")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
    assert path.read_text() == "{}\n" and [p.name for p in tmp_path.iterdir()] == ["result.json"]
