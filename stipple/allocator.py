"""Keep freed memory in the process: large runs allocate and free the same big arrays every iteration.

glibc serves every allocation above 32 MB with a fresh ``mmap`` and returns it to the system when freed. A
CG iteration at M = 10⁶ frees and allocates several gigabytes (mode grids, and the transform library's
oversampled grids), so every page of them is faulted in and zeroed by the kernel again each time: measured
there, a third of the process's CPU time was system time. ``reuse_freed_memory`` makes glibc serve large
blocks from its heap and keep what is freed for the next allocation, at the cost of a heap that does not
shrink until the process ends. The command line calls it once at start-up; the library never does.

``available_memory`` tells how much a new allocation may take (checked before large runs and pictures).
"""

import ctypes
import ctypes.util
import os

# mallopt parameters (glibc's malloc.h).
M_TRIM_THRESHOLD = -1
M_MMAP_MAX = -4
M_ARENA_MAX = -8


def running_glibc():
    """Whether this process runs on glibc (asked of the loaded C library, not read from the executable)."""
    try:
        return (os.confstr("CS_GNU_LIBC_VERSION") or "").startswith("glibc")
    except (ValueError, OSError, AttributeError):
        return False


def reuse_freed_memory():
    """Ask glibc's malloc to keep freed memory for reuse; returns False where that is not glibc.

    One arena for all threads (worker threads would otherwise map their big blocks), no ``mmap`` for large
    blocks, and no trimming of the heap. Call it before any thread allocates.
    """
    if not running_glibc():
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    settings = ((M_ARENA_MAX, 1), (M_MMAP_MAX, 0), (M_TRIM_THRESHOLD, -1))
    return all(mallopt(parameter, value) == 1 for parameter, value in settings)


def available_memory():
    """Bytes of memory available to a new allocation (MemAvailable on Linux, else physical memory)."""
    try:
        with open("/proc/meminfo") as stream:
            for line in stream:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
