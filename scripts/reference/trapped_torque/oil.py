"""The design's oil (docs/model.md section 2), written from the formulas the
document states: Walther through two datasheet points, density with thermal
expansion, exponential pressure law with bulk modulus B, gas release below
p_g as an isothermal gas ~ 1/p (Henry), softened over w = 0.1 bar."""
import math, os, sys
import numpy as np
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'meshing_zone'))
from geom import DESIGN

PATM = 101325.0
_o = DESIGN['oil']


class Oil:
    def __init__(self, T_c):
        B_ = (math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) - math.log10(math.log10(_o['nu_100c_cst'] + 0.7))) \
            / (math.log10(373.15) - math.log10(313.15))
        A_ = math.log10(math.log10(_o['nu_40c_cst'] + 0.7)) + B_ * math.log10(313.15)
        self.T = T_c
        self.nu = (10 ** (10 ** (A_ - B_ * math.log10(T_c + 273.15))) - 0.7) * 1e-6   # m^2/s
        self.rho = _o['density_20c_kg_m3'] / (1 + _o['expansion_per_k'] * (T_c - 20.0))
        self.mu = self.nu * self.rho
        self.B = _o['bulk_modulus_gpa'] * 1e9
        self.pg = _o['gas_release_bar_abs'] * 1e5
        self.Bc = _o['cavitation_modulus_bar'] * 1e5
        self.a = self.pg / self.Bc
        self.w = 0.1e5 if self.pg >= 0.2e5 else self.pg / 2
        self.pfloor = self.pg / 100
        self._v0 = self._v(PATM)
        self._lnf = self.lnrho(self.pfloor, raw=True)
        self._dlnf = self.dlnrho(self.pfloor, raw=True)

    def _v(self, p):
        x = (self.pg - p) / self.w
        sp = np.where(x > 30, x, np.log1p(np.exp(np.minimum(x, 30))))
        return np.exp(-(p - PATM) / self.B) + self.a * self.w * sp / p

    def _dv(self, p):
        x = (self.pg - p) / self.w
        sp = np.where(x > 30, x, np.log1p(np.exp(np.minimum(x, 30))))
        sig = 1 / (1 + np.exp(-np.clip(x, -60, 60)))
        return -np.exp(-(p - PATM) / self.B) / self.B + self.a * (-sig / p - self.w * sp / p ** 2)

    def lnrho(self, p, raw=False):
        """ln(rho(p) / rho_T) (relative to atmospheric)"""
        p = np.asarray(p, float)
        if raw:
            return np.log(self._v0 / self._v(p))
        pc = np.maximum(p, self.pfloor)
        val = np.log(self._v0 / self._v(pc))
        return np.where(p < self.pfloor, self._lnf + self._dlnf * (p - self.pfloor), val)

    def dlnrho(self, p, raw=False):
        p = np.asarray(p, float)
        if raw:
            return -self._dv(p) / self._v(p)
        pc = np.maximum(p, self.pfloor)
        val = -self._dv(pc) / self._v(pc)
        return np.where(p < self.pfloor, self._dlnf, val)


if __name__ == '__main__':
    for T in (40, 60, 100, 120):
        o = Oil(T)
        print(f'{T} degC: nu = {o.nu*1e6:.3f} cSt, rho = {o.rho:.2f} kg/m3, mu = {o.mu*1e3:.3f} mPa s')
    o = Oil(60)
    for p in (0.005e5, 0.02e5, 0.1e5, 0.2e5, 0.5e5, 1e5, 31e5, 150e5):
        print(f'p = {p/1e5:7.3f} bar abs: ln rho = {float(o.lnrho(p)):+.5f}, modulus = {1/float(o.dlnrho(p))/1e5:10.2f} bar')
