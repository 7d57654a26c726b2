"""Work on large arrays split into row blocks on a thread pool, the same bits for the same thread count.

numpy's element-wise operations and ``einsum`` release the GIL, so blocks of a mode grid (14 million modes at
M = 10^6) processed by several threads take a fraction of the time. Blocks depend only on the array's length and
the thread count, and sums of blocks are added in block order: the results do not depend on scheduling.
"""

import functools
from concurrent.futures import ThreadPoolExecutor

import numpy as np

# Blocks of fewer elements than this are not worth a thread: small arrays are handled in one piece.
MIN_BLOCK_SIZE = 1 << 16


@functools.cache
def thread_pool(threads):
    """The process's pool of ``threads`` worker threads (made once per count)."""
    return ThreadPoolExecutor(threads, thread_name_prefix="stipple")


@functools.cache
def term_pool(count):
    """A pool of ``count`` threads for whole terms of an objective, apart from ``thread_pool``'s: a term may hand
    its blocks to ``thread_pool`` and wait for them (one pool for both could fill with waiting terms)."""
    return ThreadPoolExecutor(count, thread_name_prefix="stipple-term")


def map_terms(function, terms):
    """``[function(term) for term in terms]``, every term on a thread of its own (``term_pool``). The terms'
    work must not itself wait on ``term_pool``."""
    return list(term_pool(len(terms)).map(function, terms))


def row_blocks(array, threads):
    """Slices of ``array``'s first axis: ``threads`` nearly equal blocks, fewer for a small array."""
    rows = len(array)
    count = max(1, min(threads, rows, np.size(array) // MIN_BLOCK_SIZE))
    edges = [rows * block // count for block in range(count + 1)]
    return [slice(edges[block], edges[block + 1]) for block in range(count)]


def map_blocks(threads, function, *arrays):
    """``[function(*(a[s] for a in arrays)) for s in row_blocks(arrays[0], threads)]``, the blocks in parallel.

    All ``arrays`` have the same length; ``function`` may write into its blocks (they are views).
    """
    blocks = row_blocks(arrays[0], threads)
    if len(blocks) == 1:
        return [function(*arrays)]
    return list(thread_pool(threads).map(lambda rows: function(*(array[rows] for array in arrays)), blocks))


def sum_blocks(threads, function, *arrays):
    """The sum of ``map_blocks``' results, added in block order (a float)."""
    return float(sum(map_blocks(threads, function, *arrays)))


def map_items(threads, function, items):
    """``[function(item) for item in items]`` on the pool (in the calling thread for one item or thread)."""
    if threads == 1 or len(items) == 1:
        return [function(item) for item in items]
    return list(thread_pool(threads).map(function, items))
