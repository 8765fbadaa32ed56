// Wendland C2 kernel in 3D (Wendland 1995; as used for SPH by Dehnen & Aly 2012):
//   W(r, h) = 21 / (16 pi h^3) (1 - q/2)^4 (2q + 1),  q = r / h,  support r < 2h.
// kernelNorm = 21 / (16 pi h^3). Both functions expect 0 <= r < 2h.
float hemo_kernel_w(float r, float h, float kernelNorm) {
  const float q = r / h;
  const float t = 1.0 - 0.5 * q;
  const float t2 = t * t;
  return kernelNorm * t2 * t2 * (2.0 * q + 1.0);
}

// dW/dr = kernelNorm * (-5 q (1 - q/2)^3) / h
float hemo_kernel_dwdr(float r, float h, float kernelNorm) {
  const float q = r / h;
  const float t = 1.0 - 0.5 * q;
  return kernelNorm * (-5.0 * q * t * t * t) / h;
}
