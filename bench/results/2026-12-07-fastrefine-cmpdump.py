import sys, math
def frames(path):
    out=[]; cur=None; last_mode=None
    for line in open(path):
        t=line.split(); mode=int(t[0]); mid=int(t[1]); c=[float.fromhex(v) for v in t[2:]]
        if cur is None or (mode==0 and last_mode==1): cur={0:{},1:{}}; out.append(cur)
        cur[mode][mid]=c; last_mode=mode
    return out
a=frames(sys.argv[1]); b=frames(sys.argv[2])
print("frames", len(a), len(b))
acc_same = all(x[0]==y[0] for x,y in zip(a,b))
print("accurate corners identical:", acc_same)
d=[]
for x,y in zip(a,b):
    for mid,c in y[1].items():
        if mid in x[0]:
            ca=x[0][mid]
            d.append(max(math.hypot(c[2*k]-ca[2*k], c[2*k+1]-ca[2*k+1]) for k in range(4)))
d.sort()
n=len(d)
print("markers", n, "worst %.4f p99 %.4f median %.5f >0.02: %d >0.005: %d" % (d[-1], d[min(n-1,int(0.99*n))], d[n//2], sum(v>0.02 for v in d), sum(v>0.005 for v in d)))
for i,(x,y) in enumerate(zip(a,b)):
    for mid,c in y[1].items():
        if mid in x[0]:
            ca=x[0][mid]
            v=max(math.hypot(c[2*k]-ca[2*k], c[2*k+1]-ca[2*k+1]) for k in range(4))
            if v>0.005:
                side=max(math.hypot(ca[2*((k+1)%4)]-ca[2*k], ca[2*((k+1)%4)+1]-ca[2*k+1]) for k in range(4))
                print("frame-block", i, "id", mid, "diff %.4f" % v, "side px %.1f" % side)
