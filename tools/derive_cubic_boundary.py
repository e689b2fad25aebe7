import sympy as sp, sys
exec(open('cub3.py').read().split("n=22")[0])

def regA(j):
    r=[0]*m
    for t,w in enumerate(a): r[2*j-4+t]=w
    return r
def regQ(i):
    c=[0]*m
    for t,w in enumerate(q):
        k=2*i-1+t
        if not (0<=k<m): return None
        c[k]=w
    return c
def regB(i):
    r=[0]*m
    for t,w in enumerate(b): r[2*i+t]=w
    return r
def derive(n, kq, kb, WQ, WB):
    global m
    m=2*n-3; s=n-3; P=Pmat(n)
    def minnorm(j,W):
        PW=P.extract(W,list(range(n))); cols=[c for c in range(n) if any(PW[:,c])]
        PW=PW.extract(list(range(len(W))),cols); M=(PW.T*PW).inv()*PW.T
        r=[0]*m
        for t,w in enumerate(W): r[w]=M[cols.index(j),t]
        return r
    Arows={0:[1]+[0]*(m-1),1:minnorm(1,list(range(7))),2:minnorm(2,list(range(7)))}
    A=sp.zeros(n,m)
    for j in range(n):
        if j in Arows: A[j,:]=sp.Matrix([Arows[j]])
        elif n-1-j in Arows: A[j,:]=sp.Matrix([Arows[n-1-j][::-1]])
        else: A[j,:]=sp.Matrix([regA(j)])
    assert A*P==sp.eye(n)
    Bregs=[regB(i) for i in range(kb,s-kb)]
    # Q boundary cols (start): min-norm with q[2i+2]=-1, A q=0, breg.q=0
    Qb=[]
    for i in range(kq):
        W=WQ(i); C=sp.Matrix.vstack(A.extract(list(range(n)),W), sp.Matrix([[r[w] for w in W] for r in Bregs]))
        # add pin row
        pin=sp.Matrix([[1 if w==2*i+2 else 0 for w in W]])
        M=sp.Matrix.vstack(C,pin); rhs=sp.zeros(M.shape[0],1); rhs[-1]=-1
        # min-norm solution of M x = rhs: x = M^T (M M^T)^+ rhs ; drop zero rows
        keep=[r for r in range(M.shape[0]) if any(M[r,:])]
        M=M.extract(keep,list(range(len(W)))); rhs=rhs.extract(keep,[0])
        # remove dependent rows
        _,piv=M.T.rref(); M=M.extract(list(piv),list(range(len(W)))); rhs=rhs.extract(list(piv),[0])
        qr=regQ(i)
        if qr is not None:
            q0=sp.Matrix([qr[w] for w in W]); x=q0+M.T*(M*M.T).inv()*(rhs-M*q0)
        else:
            x=M.T*(M*M.T).inv()*rhs
        col=[0]*m
        for t,w in enumerate(W): col[w]=x[t]
        Qb.append(col)
    Q=sp.zeros(m,s)
    for i in range(s):
        if i<kq: Q[:,i]=sp.Matrix(Qb[i])
        elif s-1-i<kq: Q[:,i]=sp.Matrix(Qb[s-1-i][::-1])
        else:
            c=regQ(i); assert c is not None; Q[:,i]=sp.Matrix(c)
    assert A*Q==sp.zeros(n,s), "AQ!=0"
    Bb=[]
    for i in range(kb):
        W=WB(i); M=sp.Matrix.hstack(P.extract(W,list(range(n))),Q.extract(W,list(range(s))))
        rhs=sp.Matrix([[0]*n+[1 if k==i else 0 for k in range(s)]])
        keep=[c for c in range(M.shape[1]) if any(M[:,c]) or rhs[c]!=0]
        M=M.extract(list(range(len(W))),keep); rhs=rhs.extract([0],keep)
        _,piv=M.rref(); M2=M.extract(list(range(len(W))),list(piv)); rhs2=rhs.extract([0],list(piv))
        x=rhs2*(M2.T*M2).inv()*M2.T if False else rhs2*M2.pinv()
        assert x*M==rhs, "B row %d inconsistent"%i
        r=[0]*m
        for t,w in enumerate(W): r[w]=x[t]
        Bb.append(r)
    B=sp.zeros(s,m)
    for i in range(s):
        if i<kb: B[i,:]=sp.Matrix([Bb[i]])
        elif s-1-i<kb: B[i,:]=sp.Matrix([Bb[s-1-i][::-1]])
        else: B[i,:]=sp.Matrix([regB(i)])
    ok=(sp.Matrix.vstack(A,B)*sp.Matrix.hstack(P,Q)==sp.eye(m))
    return ok,Arows,Qb,Bb
for kq,kb in [(2,2)]:
    try:
        ok,Ar,Qb,Bb=derive(20,kq,kb,lambda i:list(range(0,2*i+7)),lambda i:list(range(0,2*i+7)))
        print(kq,kb,'PR',ok); print(' A1',[str(v) for v in Ar[1][:8]]); print(' A2',[str(v) for v in Ar[2][:8]])
        if ok:
            f=lambda v: repr(float(sp.N(v,30)))
            print('A_START = [', [f(v) for v in Ar[1][:7]], [f(v) for v in Ar[2][:7]],']')
            for c in Qb: print(' Q',[f(v) for v in c[:8]])
            for r in Bb: print(' B',[f(v) for v in r[:7]])
    except Exception as e: print(kq,kb,"fail",e)
