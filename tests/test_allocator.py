"""The allocator setting the command line makes: freed big arrays are reused without new page faults."""

import subprocess
import sys

import pytest

from stipple.allocator import running_glibc

PROBE = """
import resource, sys
import numpy as np
from stipple.allocator import reuse_freed_memory
applied = reuse_freed_memory() if sys.argv[1] == "reuse" else None
size = 64 * 2**20 // 8  # 64 MB: above glibc's largest mmap threshold
np.ones(size)  # allocated, touched and freed
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
np.ones(size)
print(applied, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""

glibc_only = pytest.mark.skipif(not running_glibc(), reason="glibc's mallopt only")


def page_faults_of_second_array(mode):
    out = subprocess.run([sys.executable, "-c", PROBE, mode], capture_output=True, text=True, check=True).stdout
    applied, faults = out.split()
    return applied, int(faults)


@glibc_only
def test_freed_memory_is_reused_without_faults():
    pages = 64 * 2**20 // 4096
    applied, faults = page_faults_of_second_array("reuse")
    assert applied == "True"
    assert faults < 0.01 * pages


@glibc_only
def test_without_it_every_page_faults_again():
    # The oracle for the test above: by default glibc maps and unmaps such arrays each time, so the second one
    # faults at least once per page (per 2 MB page where the kernel grants numpy huge pages).
    _, faults = page_faults_of_second_array("default")
    assert faults >= 64 * 2**20 // (2 * 2**20)
