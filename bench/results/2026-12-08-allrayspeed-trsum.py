import sys
for f in sys.argv[1:]:
    t=[l.split() for l in open(f)]
    first=[r for r in t if r[0]=='0']; rounds=[r for r in t if r[0]=='1']
    mp=sum(int(r[2]) for r in t); caps=sum(int(r[3]) for r in t)
    print(f"{f}: refinements {len(first)} (unsettled {sum(r[1]=='0' for r in first)}), rounds {len(rounds)} (unsettled {sum(r[1]=='0' for r in rounds)}), model passes {mp}, fit caps {caps}")
