import sys, math
a=[l.split() for l in open(sys.argv[1])]; b=[l.split() for l in open(sys.argv[2])]
if len(a)!=len(b): print("line counts differ", len(a), len(b))
moves=[]; bad=0
for x,y in zip(a,b):
    if x[0]!=y[0]: bad+=1; continue
    m=max(math.hypot(float(x[1+2*k])-float(y[1+2*k]), float(x[2+2*k])-float(y[2+2*k])) for k in range(4))
    moves.append(m)
moves.sort(); n=len(moves)
print("n %d id-mismatch %d mean %.4f max %.3f p99 %.4f >0.002 %d >0.005 %d >0.02 %d" % (n,bad,sum(moves)/n,moves[-1],moves[int(0.99*n)],sum(m>0.002 for m in moves),sum(m>0.005 for m in moves),sum(m>0.02 for m in moves)))
