"""One step of Hairer's DOP853 (Dormand-Prince 8(5,3): 12 stages, first-same-as-last, an error
estimate blending 5th- and 3rd-order embedded solutions) and its 7th-order continuous
extension (``contd8``, three more stages, computed only for the steps that need it), in the style
of :mod:`.dopri`.

Coefficients: scipy's ``scipy/integrate/_ivp/dop853_coefficients.py`` (the same as Hairer's
Fortran ``dop853.f``), nonzero entries only, each tuple over the stages named in its comment
(k13 is the derivative at the step's end); verified by the order conditions
(``tests/test_dop853.py``).
"""

from __future__ import annotations

import math

from ..jit import kernel
from ..models.rotation import rotate
from .dopri import ZERO, combine, derivative, stage

# A2: stages 1
A2 = (5.26001519587677318785587544488e-2,)
# A3: stages 1, 2
A3 = (1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2)
# A4: stages 1, 3
A4 = (2.95875854768068491816892993775e-2, 8.87627564304205475450678981324e-2)
# A5: stages 1, 3, 4
A5 = (2.41365134159266685502369798665e-1, -8.84549479328286085344864962717e-1,
      9.24834003261792003115737966543e-1)
# A6: stages 1, 4, 5
A6 = (3.7037037037037037037037037037e-2, 1.70828608729473871279604482173e-1,
      1.25467687566822425016691814123e-1)
# A7: stages 1, 4, 5, 6
A7 = (3.7109375e-2, 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2,
      -1.7578125e-2)
# A8: stages 1, 4, 5, 6, 7
A8 = (3.70920001185047927108779319836e-2, 1.70383925712239993810214054705e-1,
      1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
      8.27378916381402288758473766002e-3)
# A9: stages 1, 4, 5, 6, 7, 8
A9 = (6.24110958716075717114429577812e-1, -3.36089262944694129406857109825,
      -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
      2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1)
# A10: stages 1, 4, 5, 6, 7, 8, 9
A10 = (4.77662536438264365890433908527e-1, -2.48811461997166764192642586468,
       -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
       1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
       -2.03312017085086261358222928593e-2)
# A11: stages 1, 4, 5, 6, 7, 8, 9, 10
A11 = (-9.3714243008598732571704021658e-1, 5.18637242884406370830023853209,
       1.09143734899672957818500254654, -8.14978701074692612513997267357,
       -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
       2.49360555267965238987089396762, -3.0467644718982195003823669022)
# A12: stages 1, 4, 5, 6, 7, 8, 9, 10, 11
A12 = (2.27331014751653820792359768449, -1.05344954667372501984066689879e1,
       -2.00087205822486249909675718444, -1.79589318631187989172765950534e1,
       2.79488845294199600508499808837e1, -2.85899827713502369474065508674,
       -8.87285693353062954433549289258, 1.23605671757943030647266201528e1,
       6.43392746015763530355970484046e-1)
# B: stages 1, 6, 7, 8, 9, 10, 11, 12
B = (5.42937341165687622380535766363e-2, 4.45031289275240888144113950566,
     1.89151789931450038304281599044, -5.8012039600105847814672114227,
     3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
     2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2)
# A14: stages 1, 7, 8, 9, 10, 11, 12, 13
A14 = (5.61675022830479523392909219681e-2, 2.53500210216624811088794765333e-1,
       -2.46239037470802489917441475441e-1, -1.24191423263816360469010140626e-1,
       1.5329179827876569731206322685e-1, 8.20105229563468988491666602057e-3,
       7.56789766054569976138603589584e-3, -8.298e-3)
# A15: stages 1, 6, 7, 8, 11, 12, 13, 14
A15 = (3.18346481635021405060768473261e-2, 2.83009096723667755288322961402e-2,
       5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2,
       -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4,
       -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1)
# A16: stages 1, 6, 7, 8, 9, 13, 14, 15
A16 = (-4.28896301583791923408573538692e-1, -4.69762141536116384314449447206,
       7.68342119606259904184240953878, 4.06898981839711007970213554331,
       3.56727187455281109270669543021e-1, -1.39902416515901462129418009734e-3,
       2.9475147891527723389556272149, -9.15095847217987001081870187138)
# E5: stages 1, 6, 7, 8, 9, 10, 11, 12
E5 = (0.1312004499419488073250102996e-1, -0.1225156446376204440720569753e+1,
      -0.4957589496572501915214079952, 0.1664377182454986536961530415e+1,
      -0.3503288487499736816886487290, 0.3341791187130174790297318841,
      0.8192320648511571246570742613e-1, -0.2235530786388629525884427845e-1)
# the 3rd-order embedded weights on stages 1, 9, 12 (E3 = B - them)
BHAT3 = (0.244094488188976377952755905512, 0.733846688281611857341361741547,
         0.220588235294117647058823529412e-1)
# D4: stages 1, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16
D4 = (-0.84289382761090128651353491142e+1, 0.56671495351937776962531783590,
      -0.30689499459498916912797304727e+1, 0.23846676565120698287728149680e+1,
      0.21170345824450282767155149946e+1, -0.87139158377797299206789907490,
      0.22404374302607882758541771650e+1, 0.63157877876946881815570249290,
      -0.88990336451333310820698117400e-1, 0.18148505520854727256656404962e+2,
      -0.91946323924783554000451984436e+1, -0.44360363875948939664310572000e+1)
# D5: stages 1, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16
D5 = (0.10427508642579134603413151009e+2, 0.24228349177525818288430175319e+3,
      0.16520045171727028198505394887e+3, -0.37454675472269020279518312152e+3,
      -0.22113666853125306036270938578e+2, 0.77334326684722638389603898808e+1,
      -0.30674084731089398182061213626e+2, -0.93321305264302278729567221706e+1,
      0.15697238121770843886131091075e+2, -0.31139403219565177677282850411e+2,
      -0.93529243588444783865713862664e+1, 0.35816841486394083752465898540e+2)
# D6: stages 1, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16
D6 = (0.19985053242002433820987653617e+2, -0.38703730874935176555105901742e+3,
      -0.18917813819516756882830838328e+3, 0.52780815920542364900561016686e+3,
      -0.11573902539959630126141871134e+2, 0.68812326946963000169666922661e+1,
      -0.10006050966910838403183860980e+1, 0.77771377980534432092869265740,
      -0.27782057523535084065932004339e+1, -0.60196695231264120758267380846e+2,
      0.84320405506677161018159903784e+2, 0.11992291136182789328035130030e+2)
# D7: stages 1, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16
D7 = (-0.25693933462703749003312586129e+2, -0.15418974869023643374053993627e+3,
      -0.23152937917604549567536039109e+3, 0.35763911791061412378285349910e+3,
      0.93405324183624310003907691704e+2, -0.37458323136451633156875139351e+2,
      0.10409964950896230045147246184e+3, 0.29840293426660503123344363579e+2,
      -0.43533456590011143754432175058e+2, 0.96324553959188282948394950600e+2,
      -0.39177261675615439165231486172e+2, -0.14972683625798562581422125276e+3)
# E3 = B - BHAT3 over the stages of B
E3 = (B[0] - BHAT3[0], B[1], B[2], B[3], B[4] - BHAT3[1], B[5], B[6], B[7] - BHAT3[2])
ORDER = 8
FIRST_STEP = 1.25  # the first step of a contact phase at rtol 1e-6, in units of 1 / omega


@kernel(inline=True)
def step(p, mode, h, start, k1, c, s, scales, rtol):
    """One step of size h; same contract as :func:`coincli.integrators.dopri.step`, except that
    the stages returned are those the continuous extension needs (k1, k6 ... k13)."""
    k2 = stage(p, mode, start, h, A2, (k1,), c, s)
    k3 = stage(p, mode, start, h, A3, (k1, k2), c, s)
    k4 = stage(p, mode, start, h, A4, (k1, k3), c, s)
    k5 = stage(p, mode, start, h, A5, (k1, k3, k4), c, s)
    k6 = stage(p, mode, start, h, A6, (k1, k4, k5), c, s)
    k7 = stage(p, mode, start, h, A7, (k1, k4, k5, k6), c, s)
    k8 = stage(p, mode, start, h, A8, (k1, k4, k5, k6, k7), c, s)
    k9 = stage(p, mode, start, h, A9, (k1, k4, k5, k6, k7, k8), c, s)
    k10 = stage(p, mode, start, h, A10, (k1, k4, k5, k6, k7, k8, k9), c, s)
    k11 = stage(p, mode, start, h, A11, (k1, k4, k5, k6, k7, k8, k9, k10), c, s)
    k12 = stage(p, mode, start, h, A12, (k1, k4, k5, k6, k7, k8, k9, k10, k11), c, s)
    used = (k1, k6, k7, k8, k9, k10, k11, k12)
    end = combine(start, h, B, used)
    c13, s13 = rotate(c, s, end[2] - start[2])
    k13 = derivative(p, mode, end, c13, s13)
    err5 = combine(ZERO, 1.0, E5, used)
    err3 = combine(ZERO, 1.0, E3, used)
    n5 = 0.0
    n3 = 0.0
    for j in range(6):
        tol = scales[j] + rtol * max(abs(start[j]), abs(end[j]))
        n5 += (err5[j] / tol) ** 2
        n3 += (err3[j] / tol) ** 2
    # Hairer's blend: |h| |err5|^2 / sqrt(|err5|^2 + 0.01 |err3|^2), as an RMS over 6 components
    err = 0.0
    if n5 > 0.0 or n3 > 0.0:
        err = abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * 6.0)
    return end, k13, c13, s13, err, (k1, k6, k7, k8, k9, k10, k11, k12, k13)


@kernel(inline=True)
def controller_memory(err):
    """What the step-size controller keeps of an accepted step for the next one:
    max(err, 1e-4)^(1/32) (five square roots, off the next step's critical path)."""
    return math.sqrt(math.sqrt(math.sqrt(math.sqrt(math.sqrt(max(err, 1e-4))))))


@kernel
def step_factor(err, memory, largest):
    """The factor for the next step, 0.9 err^(-1/8) err_prev^(1/32) within [0.2, largest]
    (three square roots, no pow()): Gustafsson's PI control, beta = 1/32 (Hairer's dop853.f
    offers it, default off: "positive values of beta (<= 0.04) make the step size control more
    stable"), with ``memory`` the previous accepted step's :func:`controller_memory` (1 after a
    rejection: the step is then cut as its error alone says). After a step whose error fell
    below the last one's the next grows less than that error alone would say: on the README's
    box throws this cuts the rejected steps from 7.1 to 2.8 a throw and the stages by 7 % at
    rtol 1e-8 on the paper's coin, by 4 % at 1e-9 on the thick one
    (benchmarks/step_control.py)."""
    if err < 1e-16:
        return largest
    return min(largest, max(0.2, 0.9 * memory / math.sqrt(math.sqrt(math.sqrt(err)))))


@kernel(inline=True)
def dense_coefficients(p, mode, start, end, h, stages, c, s):
    """The eight 6-tuples of the continuous extension of an accepted step (its start first),
    from three more stages."""
    k1, k6, k7, k8, k9, k10, k11, k12, k13 = stages
    k14 = stage(p, mode, start, h, A14, (k1, k7, k8, k9, k10, k11, k12, k13), c, s)
    k15 = stage(p, mode, start, h, A15, (k1, k6, k7, k8, k11, k12, k13, k14), c, s)
    k16 = stage(p, mode, start, h, A16, (k1, k6, k7, k8, k9, k13, k14, k15), c, s)
    f0 = (end[0] - start[0], end[1] - start[1], end[2] - start[2], end[3] - start[3],
          end[4] - start[4], end[5] - start[5])
    f1 = (h * k1[0] - f0[0], h * k1[1] - f0[1], h * k1[2] - f0[2], h * k1[3] - f0[3],
          h * k1[4] - f0[4], h * k1[5] - f0[5])
    f2 = (2.0 * f0[0] - h * (k13[0] + k1[0]), 2.0 * f0[1] - h * (k13[1] + k1[1]),
          2.0 * f0[2] - h * (k13[2] + k1[2]), 2.0 * f0[3] - h * (k13[3] + k1[3]),
          2.0 * f0[4] - h * (k13[4] + k1[4]), 2.0 * f0[5] - h * (k13[5] + k1[5]))
    every = (k1, k6, k7, k8, k9, k10, k11, k12, k13, k14, k15, k16)
    return (start, f0, f1, f2, combine(ZERO, h, D4, every), combine(ZERO, h, D5, every),
            combine(ZERO, h, D6, every), combine(ZERO, h, D7, every))


@kernel
def dense_point(rc, theta):
    """The state at fraction theta of the step, from its dense coefficients."""
    r0, f0, f1, f2, f3, f4, f5, f6 = rc
    u = 1.0 - theta
    a0 = r0[0] + theta * (f0[0] + u * (f1[0] + theta * (f2[0] + u * (
        f3[0] + theta * (f4[0] + u * (f5[0] + theta * f6[0]))))))
    a1 = r0[1] + theta * (f0[1] + u * (f1[1] + theta * (f2[1] + u * (
        f3[1] + theta * (f4[1] + u * (f5[1] + theta * f6[1]))))))
    a2 = r0[2] + theta * (f0[2] + u * (f1[2] + theta * (f2[2] + u * (
        f3[2] + theta * (f4[2] + u * (f5[2] + theta * f6[2]))))))
    a3 = r0[3] + theta * (f0[3] + u * (f1[3] + theta * (f2[3] + u * (
        f3[3] + theta * (f4[3] + u * (f5[3] + theta * f6[3]))))))
    a4 = r0[4] + theta * (f0[4] + u * (f1[4] + theta * (f2[4] + u * (
        f3[4] + theta * (f4[4] + u * (f5[4] + theta * f6[4]))))))
    a5 = r0[5] + theta * (f0[5] + u * (f1[5] + theta * (f2[5] + u * (
        f3[5] + theta * (f4[5] + u * (f5[5] + theta * f6[5]))))))
    return (a0, a1, a2, a3, a4, a5)


__all__ = ["FIRST_STEP", "ORDER", "controller_memory", "dense_coefficients", "dense_point", "step",
           "step_factor"]
