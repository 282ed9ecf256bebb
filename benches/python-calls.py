"""What a Python call costs: `gpurt.render` on the GPU (a kept device after the first
call), a `Renderer`'s frame, and `gpurt.render` on the CPU; glass.nff at 64x64, the mean
of 20 calls after a first. Run from the checkout with the module installed:

    python benches/python-calls.py after
    PYTHONPATH=/path/to/another/build python benches/python-calls.py before
"""

import gpurt, time, sys
s = 'scenes/glass.nff'
gpurt.render(s, width=64, height=64, backend='gpu')
n = 20
t = time.perf_counter()
for _ in range(n): gpurt.render(s, width=64, height=64, backend='gpu')
call = (time.perf_counter() - t) / n
r = gpurt.Renderer(s, width=64, height=64, backend='gpu'); r.render()
t = time.perf_counter()
for _ in range(n): r.render()
frame = (time.perf_counter() - t) / n
t = time.perf_counter()
for _ in range(n): gpurt.render(s, width=64, height=64, backend='cpu')
cpu = (time.perf_counter() - t) / n
print(f"{sys.argv[1]}: gpurt.render gpu {call*1e3:.1f} ms a call, Renderer {frame*1e3:.1f} ms a frame, gpurt.render cpu {cpu*1e3:.1f} ms a call")
