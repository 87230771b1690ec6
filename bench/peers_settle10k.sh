#!/usr/bin/env bash
# Times the 10k settling case in talus and in the peers of ../shared/peers (LIGGGHTS, Bullet 2)
# one after another on this machine, and prints one CSV line per code. Needs:
#   apt-get install liggghts libbullet-dev openmpi-bin
# Usage: bench/peers_settle10k.sh [build-dir]   (run from the repository root)
set -euo pipefail
build=${1:-build}
peers=$(cd "$(dirname "$0")/../.." && pwd)/shared/peers
[ -d "$peers" ] || peers=$(cd "$(dirname "$0")/.." && pwd)/../shared/peers
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "code,config,wall_s_for_0.5_s,wall_s_per_sim_s"

# talus: the settle10k case of `talus bench dem`
read -r t config < <("$build/talus" bench dem --levels D400 --quiet | python3 -c \
  'import json,sys; r=json.load(sys.stdin)["results"][-1]; print(r["wall_s"], "PoCL dt %g ms %d PGS sweeps max overlap %.2f %% of d" % (1e3 * r["dt_s"], r["iterations"], 100 * r["max_overlap_rel"]))')
echo "talus,$config,$t,$(python3 -c "print($t/0.5)")"

# liggghts: 25,000 steps of 2e-5 s, one rank and two ranks
cp "$peers"/liggghts-settle10k*.in "$work"/
cd "$work"
s=$(date +%s.%N)
liggghts -in liggghts-settle10k.in -var nsteps 25000 -log log1 -screen none
e=$(date +%s.%N)
t=$(python3 -c "print($e-$s)")
echo "liggghts,1 rank dt 2e-5 s,$t,$(python3 -c "print($t/0.5)")"
s=$(date +%s.%N)
OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --allow-run-as-root -np 2 --bind-to core \
  liggghts -in liggghts-settle10k-2ranks.in -var nsteps 25000 -log log2 -screen none
e=$(date +%s.%N)
t=$(python3 -c "print($e-$s)")
echo "liggghts,2 ranks dt 2e-5 s,$t,$(python3 -c "print($t/0.5)")"

# bullet 2: sequential-impulse PGS, 500 steps of 1 ms, 10 iterations
g++ -O2 -march=native -o pile "$peers/bullet2-settle10k.cpp" $(pkg-config --cflags --libs bullet)
s=$(date +%s.%N)
./pile --steps 500 --dt 1e-3 --iters 10 > bullet.log
e=$(date +%s.%N)
t=$(python3 -c "print($e-$s)")
echo "bullet2,btSequentialImpulse dt 1 ms 10 iterations,$t,$(python3 -c "print($t/0.5)")"
