"""Loaded into the workers of murk's LocalCluster (a Dask preload). A terminal's Ctrl-C reaches every
process of its group; the workers leave it to the client, which ends their tasks through the stop
file (murk.dask), instead of dying mid-task with a traceback each."""

import signal


def dask_setup(worker):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
