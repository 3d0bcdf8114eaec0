#!/usr/bin/python3
"""Turns the Google Benchmark JSON of hair_sim_bench and the node measurement of bench_node.py into
the benchmark table (markdown) of docs/benchmarks.md. Usage: bench_table.py BENCH.json NODE.json"""
import json
import sys

SUBSTEP_RATE = 240.0


def medians(path):
    with open(path) as f:
        data = json.load(f)
    out = {}
    for b in data['benchmarks']:
        if b.get('run_type') == 'aggregate' and b.get('aggregate_name') != 'median':
            continue
        out[b.get('run_name', b['name'])] = b
    return data.get('context', {}), out


def main():
    context, bench = medians(sys.argv[1])
    node = {}
    if len(sys.argv) > 2:
        with open(sys.argv[2]) as f:
            node = json.load(f)
    lines = ['| strips | control points | ns per control-point update (after 1 s of motion) | real-time factor at 240 Hz '
             '| strips in the exact step | exact step alone, ns per update (ratio) '
             '| 2 threads, ns per update of wall time (speed-up) |',
             '|---|---|---|---|---|---|---|']
    for name in sorted((n for n in bench if n.startswith('BM_Step/')), key=lambda n: int(n.split('/')[1])):
        b = bench[name]
        ns = 1e9 / b['items_per_second']
        points = int(b['control_points'])
        exact = bench.get(name.replace('BM_Step/', 'BM_StepExact/'))
        exact_ns = '%.0f (%.2f x)' % (1e9 / exact['items_per_second'], 1e9 / exact['items_per_second'] / ns) \
            if exact else '-'
        two = next((bench[n] for n in bench if n.split('/')[:2] == ['BM_Step2Threads', name.split('/')[1]]), None)
        two_ns = '%.0f (%.2f x)' % (1e9 / two['items_per_second'], ns / (1e9 / two['items_per_second'])) \
            if two else '-'
        lines.append('| %s | %s | %.0f | %.2f | %.1f %% | %s | %s |' % (
            format(int(b['strips']), ','), format(points, ','), ns, 1.0 / (ns * 1e-9 * points * SUBSTEP_RATE),
            100.0 * b.get('exact_share', 0.0), exact_ns, two_ns))
    # Issue 7's linear scaling: the cost per update at 10,000 strips over that at 100 (target <= 1.5).
    if 'BM_Step/100' in bench and 'BM_Step/10000' in bench:
        lines += ['', 'Cost per update at 10,000 strips / at 100: %.2f x.' % (
            bench['BM_Step/100']['items_per_second'] / bench['BM_Step/10000']['items_per_second'])]
    lines += ['', '| tessellation (default hairstyle, config/hairstyles/default.yaml, default level of detail, in one '
              'call) | ns per vertex |', '|---|---|']
    for name in ('BM_Tessellate_CachedBasis', 'BM_Tessellate_ForwardDifferencing', 'BM_Tessellate_DeBoor'):
        if name in bench:
            lines.append('| %s | %.1f |' % (name.replace('BM_Tessellate_', ''), 1e9 / bench[name]['items_per_second']))
    # The same hairstyle with one tessellate call per strip (no strips in SIMD lanes), from the same run.
    if 'BM_Tessellate_CachedBasisPerStrip' in bench and 'BM_Tessellate_CachedBasis' in bench:
        per_strip = 1e9 / bench['BM_Tessellate_CachedBasisPerStrip']['items_per_second']
        batch = 1e9 / bench['BM_Tessellate_CachedBasis']['items_per_second']
        lines.append('| CachedBasis, one call per strip (batch / this: %.2f x) | %.1f |' % (batch / per_strip, per_strip))
    # A synthetic hairstyle of the same shape whose columns are never clipped (the benchmarks' until 2026-11-26).
    if 'BM_Tessellate_CachedBasisUnclipped' in bench:
        lines.append('| CachedBasis, a synthetic hairstyle of 100 strips of 2 x 5, nothing clipped | %.1f |'
                     % (1e9 / bench['BM_Tessellate_CachedBasisUnclipped']['items_per_second']))
    # CachedBasis at more samples along (BM_Tessellate_CachedBasisAlong/<samples_along>): longer columns share
    # each strip's and each column's fixed work among more vertices.
    along = sorted((int(n.split('/')[1]), 1e9 / bench[n]['items_per_second']) for n in bench
                   if n.startswith('BM_Tessellate_CachedBasisAlong/'))
    if along:
        lines.append('| CachedBasis at samples_along %s (the default is 4) | %s |' % (
            ' / '.join(str(a) for a, _ in along), ' / '.join('%.1f' % ns for _, ns in along)))
    # The node's whole mesh per frame (tessellation, scalp, bodies, look): BM_MeshBuild/<strips>/<threads>,
    # wall time.
    mesh = {tuple(n.split('/')[1:3]): 1e9 / bench[n]['items_per_second'] for n in bench
            if n.startswith('BM_MeshBuild/')}
    if ('100', '1') in mesh:
        lines.append('| the node\'s mesh per frame (BM_MeshBuild/100: CachedBasis + scalp + bodies + look) | %.1f |'
                     % mesh[('100', '1')])
    if ('1000', '1') in mesh and ('1000', '2') in mesh:
        lines.append('| the mesh at 1,000 strips, 1 / 2 threads (wall time; speed-up) | %.1f / %.1f (%.2f x) |' % (
            mesh[('1000', '1')], mesh[('1000', '2')], mesh[('1000', '1')] / mesh[('1000', '2')]))
    if node and 'error' not in node:
        lines += ['', '| node (default hairstyle, 30 Hz, markers subscribed) | value |', '|---|---|',
                  '| CPU share of one core | %.1f %% |' % (100.0 * node['cpu_share']),
                  '| hair_markers rate | %.1f Hz |' % node['rate_hz'],
                  '| latency tf -> markers, median / p99 / max | %.1f / %.1f / %.1f ms |' % (
                      node['latency_ms_p50'], node['latency_ms_p99'], node['latency_ms_max']),
                  '| latency tf -> hair_state, median / p99 | %.1f / %.1f ms |' % (
                      node['state_latency_ms_p50'], node['state_latency_ms_p99']),
                  '| bytes per hair_markers message | %s |' % format(int(node['bytes_per_message']), ',')]
        if 'state_only_cpu_share' in node:
            lines += ['', '| node, hair_state alone subscribed (the rviz display plugin) | value |', '|---|---|',
                      '| CPU share of one core | %.1f %% |' % (100.0 * node['state_only_cpu_share']),
                      '| hair_state rate | %.1f Hz |' % node['state_only_rate_hz'],
                      '| latency tf -> hair_state, median / p99 | %.1f / %.1f ms |' % (
                          node['state_only_latency_ms_p50'], node['state_only_latency_ms_p99'])]
    elif node:
        lines += ['', 'node: ' + node['error']]
    cpu = context.get('mhz_per_cpu')
    # hair_sim_bench's own context: the instruction sets its kernels ran with (the same code is slower
    # where the CPU, or the hypervisor, hides AVX-512).
    kernels = ''
    if 'step_kernel' in context:
        kernels = '; the step\'s lanes kernel in %s, the tessellation in %s' % (
            context['step_kernel'], context.get('tessellation_kernel', '?'))
    lines += ['', 'Machine: %s CPUs%s%s; Release build; medians of %s repetitions (%s).' % (
        context.get('num_cpus', '?'), ' at %s MHz' % cpu if cpu else '', kernels,
        bench[next(iter(bench))].get('repetitions', '?') if bench else '?', context.get('date', ''))]
    print('\n'.join(lines))


if __name__ == '__main__':
    main()
