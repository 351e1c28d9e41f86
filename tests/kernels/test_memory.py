"""What keeps a scene's resident memory down: the transposed pair index only while a force
pass needs it, solved collision constants remembered on disk, glibc's large blocks
returned on free, and fresh set-up arrays taken without a copy."""

import ctypes.util
import os
import subprocess
import sys

import numba
import numpy as np
import pytest

import dpm
from dpm import _memory
from dpm.kernels import neighbours
from dpm.state import Bodies


def _spheres(threads):
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -9.81), threads=threads,
                         sphere_orientation=False)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.02, 0.02, 0.04),
                     open="+z")
    xyz = dpm.lattice((0, 0, 0), (0.02, 0.02, 0.03), 2.1e-3, jitter=5e-5, seed=2)
    sim.add_particles("sphere", material=glass, positions=xyz, radius=0.95e-3)
    return sim


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_transposed_index_only_while_needed_and_rebuilt_exactly():
    sim = _spheres(threads=1)
    sim.run(steps=300, progress=False)
    c = sim.contacts
    assert c.count > 0
    assert len(c.t_pair) == 0 and not c.t_start.any()  # the one-thread fused pass
    sim.threads = 2  # chunks: the pairs across them need the rows and the transpose
    sim.run(steps=1, progress=False)
    assert len(c.t_pair) == c.capacity
    ref_start = np.zeros_like(c.t_start)
    ref_pair = np.zeros_like(c.t_pair)
    neighbours.build_transpose(c.start, c.key, ref_start, ref_pair)
    np.testing.assert_array_equal(c.t_start, ref_start)
    np.testing.assert_array_equal(c.t_pair[:c.count], ref_pair[:c.count])
    sim.threads = 1
    sim.run(steps=1, progress=False)
    assert len(c.t_pair) == 0 and not c.t_start.any()


def test_collision_constants_remembered_without_scipy(tmp_path):
    env = {**os.environ, "DPM_CACHE_DIR": str(tmp_path)}
    code = ("import sys\n"
            "from dpm.impact.collision import tsuji_beta_for_restitution as f\n"
            "b = f(0.4137)\n"
            "print(repr(b), int(any(m.startswith('scipy.optimize._') for m in sys.modules)))\n")
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=True).stdout.split()
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                            text=True, check=True).stdout.split()
    assert first[1] == "1"  # solved: scipy was loaded
    assert second[1] == "0"  # remembered: scipy never loaded
    assert first[0] == second[0]  # the same float, bit for bit
    assert any(p.name.startswith("collisions-") for p in tmp_path.iterdir())


_RETAINED = """
import numpy as np, sys
{prelude}
def rss():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1]) / 1024
big = np.ones(16 << 17); del big          # a 16 MB block, mapped and unmapped
base = rss()
mid = np.ones(8 << 17)                    # 8 MB: from the heap once the threshold rose
small = [np.ones(64) for _ in range(1000)]  # live blocks above it
del mid
print(rss() - base)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux")
                    or ctypes.util.find_library("c") is None, reason="glibc only")
def test_large_blocks_go_back_to_the_system_when_tuned():
    def retained(prelude):
        out = subprocess.run([sys.executable, "-c", _RETAINED.format(prelude=prelude)],
                             capture_output=True, text=True, check=True)
        return float(out.stdout.split()[-1])

    plain = retained("")
    tuned = retained("from dpm._memory import tune_malloc; assert tune_malloc()")
    assert plain > 6.0  # glibc's dynamic threshold keeps the freed 8 MB resident
    assert tuned < 2.0  # with the fixed threshold it is unmapped on free
    env = {**os.environ, "DPM_MALLOC_TUNING": "0"}
    off = subprocess.run([sys.executable, "-c",
                          "from dpm._memory import tune_malloc; print(tune_malloc())"],
                         env=env, capture_output=True, text=True, check=True)
    assert off.stdout.strip() == "False"


def test_first_rows_taken_without_copy_later_rows_appended():
    b = Bodies()
    mass = np.array([1.0, 2.0])
    b.append(mass=mass)
    assert np.shares_memory(b.mass, mass)  # the fresh array itself, no copy
    b.append(mass=np.array([3]))  # an int array: converted, appended
    np.testing.assert_array_equal(b.mass, [1.0, 2.0, 3.0])
    assert b.mass.dtype == np.float64 and b.mass is not mass
    pos = np.zeros((2, 3))
    b.append(position=pos)
    assert np.shares_memory(b.position, pos) and b.position.shape == (2, 3)
    assert _memory.MMAP_THRESHOLD == 1 << 20


def test_list_beyond_int32_indices_refused():
    from dpm.state import Contacts

    c = Contacts(4, 16)
    with pytest.raises(dpm.SceneError, match="int32 pair indices"):
        c.grow(2**31)
    assert c.capacity == 16  # nothing allocated


def test_returned_ids_are_not_the_bodies_own():
    sim = _spheres(threads=1)
    ids = sim.add_particles("sphere", material=dpm.Material("m", density=1000, young=1e7,
                                                             poisson=0.3),
                            positions=[(0.5, 0.5, 0.5)], radius=1e-3)
    ids[:] = -1  # the caller's array: the scene's ids stay as they were
    assert sim.bodies.id[-1] != -1
    fresh = dpm.Simulation(dt=1e-5)
    mat = dpm.Material("m", density=1000, young=1e7, poisson=0.3)
    ids = fresh.add_particles("sphere", material=mat, positions=[(0, 0, 0), (1, 0, 0)],
                              radius=1e-3)
    ids[::-1].sort()
    np.testing.assert_array_equal(fresh.bodies.id, [0, 1])


def test_rows_of_another_shape_refused():
    b = Bodies()
    with pytest.raises(ValueError, match="rows of shape"):
        b.append(inertia=np.ones(3))  # (3,) where rows of 3 are expected
