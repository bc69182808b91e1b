import sys
for f in sys.argv[1:]:
    d=[float(l.split()[-1]) for l in open(f) if l.startswith('PROBE')]
    d.sort(); n=len(d)
    print("%-28s n %d mean %.5f median %.5f >0.002 %d >0.005 %d >0.01 %d >0.02 %d" % (f, n, sum(d)/n, d[n//2], sum(x>0.002 for x in d), sum(x>0.005 for x in d), sum(x>0.01 for x in d), sum(x>0.02 for x in d)))
