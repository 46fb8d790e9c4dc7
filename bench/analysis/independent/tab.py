#!/usr/bin/python3
"""Tabulates rig analyze's noise terms over records of gen.py's sets (written by the helper-59
review): per set and term, reported, bounds holding the truth, nulls, upper limits holding it,
> 3x off with bounds excluding, values where the truth is 0 (and with a lower bound above 0), the
median ratio; then the pooled coverage of the dominant terms (>= 50 % of the model's sigma^2 at
some octave tau <= T/4) and the ways B was read.

    tab.py DIR     DIR/SET/I.json, the JSON of rig analyze --json
"""
import json, sys, glob, os, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gen import SETS, avar_model
def dom(p):
    T=p['hours']*3600; fs=p['fs']
    taus=[2**k/fs for k in range(40) if 2**k/fs<=T/4]
    d={}
    for t in 'QNBKR':
        d[t]=any(avar_model(np.array(tau),**{t:p[t]})>=0.5*avar_model(np.array(tau),**{k:p[k] for k in 'QNBKR'}) for tau in taus) if p[t] else False
    return d
rows=[]; pool=[0,0]; psdr={}
methods={}
for S,p in SETS.items():
    files=sorted(glob.glob(os.path.join(sys.argv[1], S, '*.json')),key=lambda f:int(os.path.basename(f)[:-5]))
    if not files: continue
    D=dom(p)
    js=[json.load(open(f)) for f in files]
    for name,tk,get in [('Q','Q',lambda nt:nt['Q']),('N','N',lambda nt:nt['N']),('B(paper)','B',lambda nt:nt['B']),('B(model)','B',lambda nt:nt['B_lsq']),('K','K',lambda nt:nt['K']),('R','R',lambda nt:nt['R'])]:
        truth=p[tk]; n=len(js); rep=cov=nul=ul=ulh=x3=fp=fplo=0; ratios=[]; excl=[]
        for j,js_ in enumerate(js):
            t=get(js_['noise_terms']); v=t.get('value'); lo=t.get('lo'); hi=t.get('hi')
            if v is None:
                nul+=1
                if hi is not None and truth>0:
                    ul+=1; ulh+= hi>=truth
                continue
            rep+=1
            if truth==0:
                fp+=1; fplo+= (lo is not None and lo>0); continue
            r=v/truth; ratios.append(r)
            if lo is not None and hi is not None and lo<=truth<=hi: cov+=1
            else:
                excl.append((j,round(r,2)))
                if r>3 or r<1/3: x3+=1
        dm = D[tk]
        if dm and name!='B(paper)': pool[0]+=cov; pool[1]+=n
        rows.append((S,name,truth,'dom' if dm else ('inj' if truth else 'zero'),n,rep,cov,nul,f'{ulh}/{ul}',x3,fp,fplo,np.median(ratios) if ratios else float('nan'),excl))
    methods[S]={}
    for js_ in js:
        m=js_['noise_terms']['b_method']; methods[S][m]=methods[S].get(m,0)+1
    if 'psd' in js[0] and js[0]['psd'] and p['N']:
        r=np.array([x['psd']['n_from_psd']/p['N'] for x in js]); psdr[S]=r
print(f"{'set':9} {'term':9} {'truth':>9} {'kind':4} {'n':>2} {'rep':>3} {'cov':>3} {'null':>4} {'UL ok':>5} {'>3x':>3} {'FP':>2} {'FPlo>0':>6} {'med':>6}  excluded(seed,ratio)")
for r in rows:
    print(f"{r[0]:9} {r[1]:9} {r[2]:9.3g} {r[3]:4} {r[4]:2d} {r[5]:3d} {r[6]:3d} {r[7]:4d} {r[8]:>5} {r[9]:3d} {r[10]:2d} {r[11]:6d} {r[12]:6.3f}  {r[13][:8]}")
print('pooled dominant (model terms, B(model), R drift):',pool, f'{100*pool[0]/max(pool[1],1):.1f}%')
print('b_method:',methods)
for S,r in psdr.items(): print('PSD N/truth',S,'median %.4f min %.4f max %.4f within10%% %d/%d'%(np.median(r),r.min(),r.max(),(abs(r-1)<0.1).sum(),len(r)))
