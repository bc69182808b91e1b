import math, sys
def readpgm(fn):
    d=open(fn,'rb').read()
    parts=[]; i=0
    while len(parts)<4:
        while d[i:i+1].isspace(): i+=1
        if d[i:i+1]==b'#':
            while d[i:i+1]!=b'\n': i+=1
            continue
        j=i
        while not d[j:j+1].isspace(): j+=1
        parts.append(d[i:j]); i=j
    i+=1
    w,h=int(parts[1]),int(parts[2])
    return w,h,d[i:]
def samp(img,x,y):
    w,h,d=img
    x0=int(math.floor(x)); y0=int(math.floor(y)); fx=x-x0; fy=y-y0
    if x0<0 or y0<0 or x0+1>=w or y0+1>=h: return None
    v=lambda X,Y: d[Y*w+X]
    return (v(x0,y0)*(1-fx)*(1-fy)+v(x0+1,y0)*fx*(1-fy)+v(x0,y0+1)*(1-fx)*fy+v(x0+1,y0+1)*fx*fy)
def angle(c,k):
    p=c[k]; a=c[(k+3)%4]; b=c[(k+1)%4]
    ux,uy=a[0]-p[0],a[1]-p[1]; vx,vy=b[0]-p[0],b[1]-p[1]
    return math.degrees(math.acos((ux*vx+uy*vy)/math.hypot(ux,uy)/math.hypot(vx,vy)))
lo,hi=float(sys.argv[2]),float(sys.argv[3])
img=-1; imgs={}; acc={}
us=[i*0.25 for i in range(-16,17)]
for line in open(sys.argv[1]):
    t=line.split()
    if t[0]=='IMG': img+=1; cur=readpgm(f'{sys.argv[4]}/{img}.pgm')
    elif t[0]=='TRUTH':
        v=list(map(float,t[1:])); c=[(v[3+2*k],v[4+2*k]) for k in range(4)]
        if not(lo<=v[1]<hi and 55<=v[2]<=70): continue
        cx=sum(p[0] for p in c)/4; cy=sum(p[1] for p in c)/4
        for k in range(4):
            a=c[k]; b=c[(k+1)%4]; L=math.hypot(b[0]-a[0],b[1]-a[1]); dx=(b[0]-a[0])/L; dy=(b[1]-a[1])/L
            n=(dy,-dx)
            if n[0]*((a[0]+b[0])/2-cx)+n[1]*((a[1]+b[1])/2-cy)<0: n=(-n[0],-n[1])
            ext=0.5*(abs(n[0]*(c[(k+2)%4][0]-a[0])+n[1]*(c[(k+2)%4][1]-a[1]))+abs(n[0]*(c[(k+3)%4][0]-a[0])+n[1]*(c[(k+3)%4][1]-a[1])))
            cp=ext/8
            acute0 = angle(c,k)<angle(c,(k+1)%4)
            for name,f in (('acute col1',1.65/8),('acute col2',2.5/8),('mid',0.5),('obtuse col2',5.5/8),('obtuse col1',6.35/8)):
                t_= f if acute0 else 1-f
                px=a[0]+t_*(b[0]-a[0]); py=a[1]+t_*(b[1]-a[1])
                prof=[samp(cur,px+u*n[0],py+u*n[1]) for u in us]
                if None in prof: continue
                s=acc.setdefault(name,[[0.0]*len(us),0,0.0]); s[1]+=1; s[2]+=cp
                for i,p in enumerate(prof): s[0][i]+=p
print("u px:   "+" ".join(f"{u:6.2f}" for u in us[::2]))
for name in ('acute col1','acute col2','mid','obtuse col2','obtuse col1'):
    s=acc[name]; print(f"{name:11s} n {s[1]} cell {s[2]/s[1]:.2f}: "+" ".join(f"{x/s[1]:6.1f}" for x in s[0][::2]))
