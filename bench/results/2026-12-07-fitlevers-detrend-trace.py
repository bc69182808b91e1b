import sys, statistics as st
def pct(a,q):
    a=sorted(a); return a[min(len(a)-1,int(q/100*len(a)))]
for f in sys.argv[1:]:
    rows=[l.split() for l in open(f)]
    rel=[float(r[4]) for r in rows]; de=[float(r[6]) for r in rows]; ev=[int(r[10]) for r in rows]
    ade=[abs(x) for x in de]; E=sum(ev)
    print(f, "refits", len(rows), "evals", E, "mean", round(E/len(rows),2), "|de| median", round(st.median(ade),5), "p90", round(pct(ade,90),5), "mean signed", f"{st.mean(de):+.5f}")
    for t in [0.002,0.005,0.01,0.02,0.05]:
        idx=[i for i in range(len(rows)) if rel[i]<t]
        if not idx: print(f"  rel<{t}: 0"); continue
        print(f"  rel<{t}: {len(idx)} refits ({100*len(idx)/len(rows):.1f} %), evals {sum(ev[i] for i in idx)} ({100*sum(ev[i] for i in idx)/E:.1f} %), |de| max {max(ade[i] for i in idx):.5f} mean {st.mean(ade[i] for i in idx):.5f} signed {st.mean(de[i] for i in idx):+.6f}")
    print("  rel pct 10/50/90", [round(pct(rel,q),4) for q in (10,50,90)])
