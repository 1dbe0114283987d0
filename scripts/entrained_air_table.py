"""The entrained-air table of docs/model.md section 2: eta_v, eta_hm and the
lowest pocket pressure (absolute, from the trace) with 3 % of free air, at
30 bar and the listed speeds, temperatures and inlet pressures.

    python3 scripts/entrained_air_table.py target/release/gearpump
"""
import json, subprocess, sys, csv, tempfile, os
exe = sys.argv[1]
for p, n, t, pin in [(30,4000,60,1.01325),(30,4000,120,1.01325),(30,4000,60,0.6),(30,4000,60,0.3),(30,4000,60,0.2),(30,2000,60,0.2)]:
    d = tempfile.mkdtemp()
    r = subprocess.run([exe, "simulate", "--speed", str(n), "--pressure", str(p), "--temp", str(t), "--inlet-pressure", str(pin), "--set", "oil.air_fraction=0.03", "--json", "--trace", d], capture_output=True, text=True)
    if r.returncode:
        print(p, n, t, pin, "FAILED", r.stderr.strip()[:300]); continue
    j = json.loads(r.stdout)
    pmin = min(float(v) for row in csv.DictReader(open(os.path.join(d, "trace.csv"))) for k, v in row.items() if k.startswith("p_driv"))
    print(f"{p:3d} bar {n:5d} rpm {t:4d} C pin {pin:.2f}: eta_v {j['eta_v']:.5f} eta_hm {j['eta_hm']:.5f} pmin {pmin+pin:+.4f} bar abs newton {j['newton_iterations_mean']:.2f}")
