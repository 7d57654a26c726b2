"""Outputs are all-or-nothing: a failed write (disk full, stdout full) leaves every earlier output as it was."""

import errno
import os
import subprocess

import pytest
from safety_helpers import FAST, invoke, leftovers, make_image, refused, snapshot

import stipple.io.commit
from stipple.errors import StippleError
from stipple.io.commit import StagedOutputs

OUTPUTS = ["-o", "a.csv", "-o", "b.svg", "-o", "c.png"]


@pytest.fixture
def folder(tmp_path):
    make_image(tmp_path / "in.png")
    for name in ("a.csv", "b.svg", "c.png"):
        (tmp_path / name).write_text(f"old {name}\n")
    return tmp_path


def failing_on_call(number, function):
    """``function`` that raises ENOSPC on its ``number``-th call."""
    calls = []

    def wrapper(*args):
        calls.append(args)
        if len(calls) == number:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return function(*args)

    return wrapper


@pytest.mark.parametrize("failing_call", [1, 2, 3])
def test_a_failed_write_leaves_every_output_untouched(folder, monkeypatch, failing_call):
    monkeypatch.setattr(os, "fsync", failing_on_call(failing_call, os.fsync))
    refused(["torus", "in.png", *FAST, *OUTPUTS], folder, "No space left on device")


def test_a_failed_rename_removes_the_remaining_temporaries(folder, monkeypatch):
    monkeypatch.setattr(os, "replace", failing_on_call(1, os.replace))
    refused(["torus", "in.png", *FAST, *OUTPUTS], folder, "cannot write")


@pytest.mark.parametrize("failing_call", [1, 2, 3])
def test_a_rename_failing_after_others_puts_every_output_back(folder, monkeypatch, failing_call):
    # Calls 1, 2 and 3 are the renames of a.csv, b.svg and c.png: 2 and 3 fail after one or two outputs were
    # already in place.
    monkeypatch.setattr(os, "replace", failing_on_call(failing_call, os.replace))
    refused(["torus", "in.png", *FAST, *OUTPUTS], folder, "cannot write")


def test_no_output_is_ever_missing_while_the_outputs_are_renamed(tmp_path, monkeypatch):
    """A reader (or a crash) between two renames must find every target, old or new: setting the old files aside
    by renaming them left each target missing for a moment."""
    targets = [tmp_path / name for name in ("a.csv", "b.svg", "c.png")]
    for target in targets:
        target.write_text("old\n")
    real = os.replace

    def watched(source, destination):
        assert all(target.exists() for target in targets)
        real(source, destination)
        assert all(target.exists() for target in targets)

    monkeypatch.setattr(os, "replace", watched)
    stipple.io.commit.commit_outputs([(target, b"new\n") for target in targets])
    assert all(target.read_text() == "new\n" for target in targets) and not leftovers(tmp_path)


def test_an_old_file_that_cannot_be_put_back_is_named_and_kept(tmp_path, monkeypatch):
    (tmp_path / "a.csv").write_text("old a\n")
    (tmp_path / "b.svg").write_text("old b\n")
    real, calls = os.replace, []

    def failing_from_the_second(source, destination):  # b.svg's rename fails, then putting a.csv back fails
        calls.append(destination)
        if len(calls) > 1:
            raise OSError(errno.EROFS, os.strerror(errno.EROFS))
        real(source, destination)

    monkeypatch.setattr(os, "replace", failing_from_the_second)
    with pytest.raises(StippleError, match="b.svg: cannot write .Read-only file system.; the old file is kept as"):
        stipple.io.commit.commit_outputs([(tmp_path / "a.csv", b"new a\n"), (tmp_path / "b.svg", b"new b\n")])
    kept = [path for path in tmp_path.iterdir() if path.suffix == ".old"]
    assert len(kept) == 1 and kept[0].read_text() == "old a\n" and (tmp_path / "b.svg").read_text() == "old b\n"


def test_a_new_output_whose_rename_fails_is_reported_in_one_line(tmp_path, monkeypatch):
    """A new output (no old file) whose name could not be removed in the rollback (too long) put None among the
    old files to name: a TypeError traceback after the whole run (a hostile review)."""
    (tmp_path / "a.csv").write_text("old a\n")
    real = os.replace

    def refusing_the_new_name(source, destination):
        if str(destination).endswith("new.csv"):
            raise OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG))
        real(source, destination)

    remove = stipple.io.commit._remove

    def unremovable(path):
        if str(path).endswith("new.csv"):
            raise OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG))
        remove(path)

    monkeypatch.setattr(os, "replace", refusing_the_new_name)
    monkeypatch.setattr(stipple.io.commit, "_remove", unremovable)
    with pytest.raises(StippleError, match="new.csv: cannot write .File name too long.$"):
        stipple.io.commit.commit_outputs([(tmp_path / "a.csv", b"new a\n"), (tmp_path / "new.csv", b"new\n")])


def test_a_name_too_long_for_the_folder_is_refused_before_the_run(folder):
    name = "a" * 300 + ".csv"
    refused(["torus", "in.png", *FAST, *OUTPUTS, "-o", name], folder, "the file name is 304 bytes")


def test_a_folder_made_where_a_staged_output_goes_is_refused_with_nothing_renamed(tmp_path):
    (tmp_path / "a.csv").write_text("old\n")
    with pytest.raises(StippleError, match="b.png: cannot write .it is a folder"), StagedOutputs() as staged:
        staged.add(tmp_path / "a.csv", b"new\n")
        staged.add(tmp_path / "b.png", b"new\n")
        (tmp_path / "b.png").mkdir()
        staged.commit()
    assert (tmp_path / "a.csv").read_text() == "old\n" and not leftovers(tmp_path)


def test_render_and_evaluate_commit_together(folder, monkeypatch):
    (folder / "p.csv").write_text("x,y\n1.5,2.5\n3.5,7.5\n9.5,4.5\n")
    (folder / "r.json").write_text("old report\n")
    monkeypatch.setattr(os, "fsync", failing_on_call(2, os.fsync))
    refused(["render", "p.csv", "--size", "16,12", *OUTPUTS], folder, "No space left")
    monkeypatch.setattr(os, "fsync", failing_on_call(2, os.fsync))
    refused(["evaluate", "p.csv", "in.png", "--json", "r.json", "--spectrum", "c.png"], folder, "No space left")


def test_a_full_stdout_leaves_the_files_untouched(folder):
    before = snapshot(folder)
    with open("/dev/full", "w") as full:
        result = subprocess.run(
            [os.sys.executable, "-m", "stipple", "torus", "in.png", *FAST, "-o", "a.csv", "-o", "-"],
            cwd=folder,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
        )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == ["Error: cannot write to stdout (No space left on device)"]
    assert snapshot(folder) == before and leftovers(folder) == []


def test_a_reader_that_stops_part_way_is_a_failed_write(folder):
    """A pipe whose reader stops after 1000 bytes took a short write without an error: the CSV was cut, the
    process exited 0 and the other outputs were replaced (a hostile sweep)."""
    before = snapshot(folder)
    fast = ["-N", "16", "--iterations", "1", "-q", "--seed", "1"]
    process = subprocess.Popen(
        [os.sys.executable, "-m", "stipple", "torus", "in.png", "-M", "8000", *fast, "-o", "-", "-o", "a.csv"],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert len(process.stdout.read(1000)) == 1000
    process.stdout.close()
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=120) == 1
    assert stderr.strip().splitlines() == ["Error: cannot write to stdout (Broken pipe)"]
    assert snapshot(folder) == before and leftovers(folder) == []


def with_stdout_closed(arguments, folder):
    """``stipple arguments`` as a process started without a standard output."""
    return subprocess.run(
        [os.sys.executable, "-m", "stipple", *arguments],
        cwd=folder,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        close_fds=True,
        preexec_fn=lambda: os.close(1),
    )


def test_a_closed_stdout_is_refused_before_the_run(folder):
    before = snapshot(folder)
    result = with_stdout_closed(["torus", "in.png", *FAST, "-o", "a.csv", "-o", "-"], folder)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == ["Error: cannot write to stdout: it is closed"]
    assert snapshot(folder) == before and leftovers(folder) == []


@pytest.mark.parametrize("arguments", [["--help"], ["torus", "-h"], ["--version"]])
def test_help_to_a_closed_stdout_is_an_error_not_silence(folder, arguments):
    # It printed nothing and exited 0 (a hostile sweep).
    result = with_stdout_closed(arguments, folder)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == ["Error: cannot write to stdout: it is closed"]


@pytest.fixture
def small_filesystem(tmp_path):
    """A 64 KiB tmpfs (needs root and permission to mount; skipped otherwise)."""
    mount_point = tmp_path / "small"
    mount_point.mkdir()
    try:
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount_point)],
            check=True,
            capture_output=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError) as error:
        pytest.skip(f"cannot mount a small tmpfs here (needs root and CAP_SYS_ADMIN): {error}")
    try:
        yield mount_point
    finally:
        subprocess.run(["umount", str(mount_point)], check=False, capture_output=True, timeout=10)


def fill(directory, leave):
    """Fill the filesystem of ``directory`` until only ``leave`` bytes (page-rounded) stay free."""
    handle = os.open(directory / "filler", os.O_WRONLY | os.O_CREAT)
    try:
        while os.write(handle, b"\0" * 4096):
            pass
    except OSError:
        pass
    finally:
        os.close(handle)
    size = (directory / "filler").stat().st_size
    os.truncate(directory / "filler", max(size - leave, 0))


def test_on_a_really_full_filesystem_nothing_is_clobbered(folder, small_filesystem):
    for name in ("a.csv", "b.svg", "c.png"):
        (small_filesystem / name).write_text(f"old {name}\n")
    fill(small_filesystem, 8192)  # room for the CSV and the SVG of 30 dots, not for the PNG
    before = snapshot(small_filesystem)
    outputs = [arg if arg == "-o" else str(small_filesystem / arg) for arg in OUTPUTS]
    result = invoke(["torus", "in.png", *FAST, *outputs], folder)
    assert result.exit_code == 1 and "No space left on device" in result.stderr, result.output
    assert len(result.stderr.strip().splitlines()) == 1
    assert snapshot(small_filesystem) == before and leftovers(small_filesystem) == []
    os.unlink(small_filesystem / "filler")
    assert invoke(["torus", "in.png", *FAST, *outputs], folder).exit_code == 0
    assert (small_filesystem / "c.png").read_bytes().startswith(b"\x89PNG")


def test_stdout_item_is_written_before_files_are_renamed(tmp_path, monkeypatch):
    (tmp_path / "a.csv").write_text("old\n")

    def broken(data):
        raise stipple.io.commit.StippleError("cannot write to stdout (Broken pipe)")

    monkeypatch.setattr(stipple.io.commit, "write_stdout", broken)
    with pytest.raises(stipple.io.commit.StippleError):
        stipple.io.commit.commit_outputs([(str(tmp_path / "a.csv"), b"new\n"), ("-", b"x")])
    assert (tmp_path / "a.csv").read_text() == "old\n" and leftovers(tmp_path) == []


def test_outputs_and_checkpoints_are_written_through_symbolic_links(folder):
    """Renamed over a link, a resumed checkpoint's link became a file of its own and its file kept the old state,
    which the next resume through the real name read (a hostile review); outputs through links alike."""
    (folder / "sub").mkdir()
    (folder / "sub" / "real.csv").write_text("old\n")
    os.symlink("sub/real.csv", folder / "link.csv")
    os.symlink("sub/none.csv", folder / "dangling.csv")  # its file does not exist yet
    os.symlink("sub/run.npz", folder / "run.npz")
    args = ["torus", "in.png", *FAST, "-o", "link.csv", "-o", "dangling.csv", "--checkpoint", "run.npz"]
    assert invoke(args, folder).exit_code == 0
    for link, real in (("link.csv", "real.csv"), ("dangling.csv", "none.csv"), ("run.npz", "run.npz")):
        assert (folder / link).is_symlink() and (folder / "sub" / real).is_file()
    assert (folder / "sub" / "real.csv").read_text().startswith("x,y")
    written = (folder / "sub" / "run.npz").read_bytes()
    resumed = ["torus", "in.png", "-M", "30", "-N", "8", "--iterations", "4", "-q", "-o", "link.csv"]
    assert invoke([*resumed, "--checkpoint", "run.npz", "--resume"], folder).exit_code == 0
    assert (folder / "run.npz").is_symlink() and (folder / "sub" / "run.npz").read_bytes() != written
    assert leftovers(folder) == [] and leftovers(folder / "sub") == []


@pytest.mark.parametrize("role", [["-o", "loop.csv"], ["-o", "a.csv", "--checkpoint", "loop.npz"]])
def test_an_output_or_checkpoint_through_a_loop_of_links_is_refused(folder, role):
    """A loop of links was replaced by a regular file, exit 0 (a hostile sweep); reading through one is refused."""
    name = role[-1]
    os.symlink("other" + name[4:], folder / name)
    os.symlink(name, folder / ("other" + name[4:]))
    before = snapshot(folder)
    result = invoke(["torus", "in.png", *FAST, *role], folder)
    assert result.exit_code == 1 and f"{name}: a loop of symbolic links" in result.stderr
    assert snapshot(folder) == before and (folder / name).is_symlink() and leftovers(folder) == []
