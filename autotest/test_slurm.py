"""A Slurm job array of gdal_watermesh shards on this machine: munge,
slurmctld and slurmd from Debian's munge and slurm-wlm (installed by
bootstrap.sh) started by the test on localhost with one node of every CPU,
the array script of docs/distributed.md submitted with sbatch --wait, the
shards merged in order: the single run's features exactly."""

import os
import shutil
import socket
import subprocess
import time

import pytest

from test_shards import ARGS, CLI_PATH, features, merge, single  # noqa: F401 (fixture)

DAEMONS = ('/usr/sbin/munged', '/usr/sbin/slurmctld', '/usr/sbin/slurmd', '/usr/bin/sbatch')


def munge_works():
    p = subprocess.run('munge -n | unmunge', shell=True, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE)
    return p.returncode == 0


@pytest.fixture(scope='module')
def slurm(tmp_path_factory):
    missing = [d for d in DAEMONS if not os.access(d, os.X_OK)]
    assert not missing, '%s missing: bootstrap.sh installs munge and slurm-wlm' % missing
    d = tmp_path_factory.mktemp('slurm')
    host = socket.gethostname().split('.')[0]
    conf = d / 'slurm.conf'
    conf.write_text('\n'.join([
        'ClusterName=watermesh', 'SlurmctldHost=%s' % host, 'SlurmUser=root',
        'SlurmdUser=root', 'AuthType=auth/munge', 'CredType=cred/munge',
        'ProctrackType=proctrack/linuxproc', 'TaskPlugin=task/none', 'MpiDefault=none',
        'ReturnToService=2', 'SlurmctldPort=16917', 'SlurmdPort=16918',
        'SlurmctldPidFile=%s/slurmctld.pid' % d, 'SlurmdPidFile=%s/slurmd.pid' % d,
        'SlurmdSpoolDir=%s/spool' % d, 'StateSaveLocation=%s/state' % d,
        'SlurmctldLogFile=%s/slurmctld.log' % d, 'SlurmdLogFile=%s/slurmd.log' % d,
        'SchedulerType=sched/backfill', 'SelectType=select/cons_tres',
        'SelectTypeParameters=CR_Core', 'JobCompType=jobcomp/none',
        'AccountingStorageType=accounting_storage/none',
        'NodeName=%s CPUs=%d State=UNKNOWN' % (host, os.cpu_count()),
        'PartitionName=wm Nodes=%s Default=YES MaxTime=INFINITE State=UP' % host, '']))
    for sub in ('spool', 'state'):
        (d / sub).mkdir()
    env = dict(os.environ, SLURM_CONF=str(conf))
    started_munge = False
    if not munge_works():
        os.makedirs('/run/munge', exist_ok=True)
        subprocess.run(['/usr/sbin/munged', '--force'], check=True)
        started_munge = True
        for _ in range(50):
            if munge_works():
                break
            time.sleep(0.1)
    subprocess.run(['/usr/sbin/slurmctld', '-f', str(conf)], env=env, check=True)
    subprocess.run(['/usr/sbin/slurmd', '-f', str(conf)], env=env, check=True)
    try:
        for _ in range(100):
            p = subprocess.run(['sinfo', '-h', '-o', '%T'], env=env, stdout=subprocess.PIPE,
                               universal_newlines=True)
            if p.stdout.strip() == 'idle':
                break
            time.sleep(0.2)
        assert p.stdout.strip() == 'idle', (p.stdout, (d / 'slurmctld.log').read_text()[-2000:])
        yield env, d
    finally:
        subprocess.run(['scontrol', 'shutdown'], env=env)
        time.sleep(1)
        for pid in ('slurmd.pid', 'slurmctld.pid'):
            if (d / pid).exists():
                subprocess.run(['kill', (d / pid).read_text().strip()])
        if started_munge:
            subprocess.run(['pkill', '-x', 'munged'])


def test_slurm_job_array(slurm, tmp_path, single):  # noqa: F811
    env, d = slurm
    out = tmp_path / 'out'
    out.mkdir()
    script = tmp_path / 'shards.sh'
    script.write_text('#!/bin/sh\n#SBATCH --array=0-3\n#SBATCH --cpus-per-task=1\n'
                      '#SBATCH --output=%s/job_%%a.log\n'
                      'exec %s -q -resume -num_threads 1 %s -shard 4 '
                      '-shard-env SLURM_ARRAY_TASK_ID -shard-plan %s/plan.txt '
                      '%s/shard_$SLURM_ARRAY_TASK_ID.gpkg\n'
                      % (out, CLI_PATH, ' '.join(ARGS), tmp_path, out))
    p = subprocess.run(['sbatch', '--wait', str(script)], env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    logs = {f: (out / f).read_text() for f in os.listdir(out) if f.endswith('.log')}
    assert p.returncode == 0, (p.stdout, p.stderr, logs)
    shards = [str(out / ('shard_%d.gpkg' % i)) for i in range(4)]
    assert all(os.path.exists(s) for s in shards), (os.listdir(out), logs)
    merged = str(tmp_path / 'merged.gpkg')
    merge(shards, merged)
    assert features(merged) == single
