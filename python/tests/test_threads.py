"""The GIL is released while C++ steps: two threads step two simulations in
parallel and get what one thread gets; one simulation refuses a second
thread instead of racing."""

import threading

import numpy as np

import terracut


def scenario(exp1):
    return terracut.Scenario.load(exp1).with_overrides(resolution=40)


def test_two_threads_step_two_simulations_and_match_one_thread(exp1):
    sc = scenario(exp1)
    poses = sc.cut_poses("horizontal")
    chunks = np.array_split(poses, 8)

    # One thread, one simulation after the other: the reference.
    reference = []
    for _ in range(2):
        sim = terracut.Simulation(sc)
        cols = [sim.step(c)["contact_length"] for c in chunks]
        reference.append((np.concatenate(cols), sim.state_hash))

    sims = [terracut.Simulation(sc) for _ in range(2)]
    progress = [0, 0]
    results = [None, None]
    start = threading.Barrier(2)

    def work(k):
        start.wait()
        cols = []
        for c in chunks:
            cols.append(sims[k].step(c)["contact_length"])
            progress[k] += 1
        results[k] = np.concatenate(cols)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert progress == [len(chunks), len(chunks)]  # both threads finished every chunk
    for k in range(2):
        np.testing.assert_array_equal(results[k], reference[k][0])
        assert sims[k].state_hash == reference[k][1]


def test_a_second_thread_on_the_same_simulation_is_refused_not_raced(exp1):
    # While one thread is inside a long batched step (GIL released), the main
    # thread runs Python and its own step() on the same simulation is refused
    # with a clear error. Were the GIL held, the main thread could not run
    # until the batch was over and would never see the simulation busy.
    sc = scenario(exp1)
    sim = terracut.Simulation(sc)
    poses = np.tile(sc.cut_poses("horizontal"), (40, 1))  # 80k steps
    done = threading.Event()
    inside = threading.Event()

    def long_batch():
        inside.set()
        sim.step(poses)
        done.set()

    t = threading.Thread(target=long_batch)
    t.start()
    inside.wait()
    refused = None
    while t.is_alive() and not done.is_set() and refused is None:
        try:
            sim.contact([0.5, 0.1, 0.5, 1, 0, 0, 0])
        except RuntimeError as e:
            refused = str(e)
    t.join(timeout=120)
    assert refused is not None and "another thread" in refused
    assert sim.step_count == len(poses)
