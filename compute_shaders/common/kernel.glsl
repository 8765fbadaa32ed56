// Wendland C2 kernel in 3D (Wendland 1995; as used for SPH by Dehnen & Aly 2012):
//   W(r, h) = 21 / (16 pi h^3) (1 - q/2)^4 (2q + 1),  q = r / h,  support r < 2h.
// kernelNorm = 21 / (16 pi h^3). hemo_kernel_w expects 0 <= r < 2h.
float hemo_kernel_w(float r, float h, float kernelNorm) {
  const float q = r / h;
  const float t = 1.0 - 0.5 * q;
  const float t2 = t * t;
  return kernelNorm * t2 * t2 * (2.0 * q + 1.0);
}

// The same with 1 / h given (the pair loops' form: a multiplication, not a division, per pair).
float hemo_kernel_w_inv(float r, float invH, float kernelNorm) {
  const float q = r * invH;
  const float t = 1.0 - 0.5 * q;
  const float t2 = t * t;
  return kernelNorm * t2 * t2 * (2.0 * q + 1.0);
}

// W / kernelNorm, (1 - q/2)^4 (2q + 1) = (1 - s)^4 (4s + 1) with s = q/2 = r halfInvH
// (halfInvH = 1 / 2h), for sums that apply the norm once at the end.
float hemo_kernel_w_shape(float r, float halfInvH) {
  const float s = r * halfInvH;
  const float t = 1.0 - s;
  const float t2 = t * t;
  return t2 * t2 * (4.0 * s + 1.0);
}

// The same, 0 from the support on, and 0 everywhere when `live` is 0: (max(live - s, 0))^4
// (4s + 1) with live 1 (an entry to count) or 0 (the padding of a list texel), which the
// cluster passes thus drop without a test per pair.
float hemo_kernel_w_shape_live(float r, float halfInvH, float live) {
  const float s = r * halfInvH;
  const float t = max(live - s, 0.0);
  const float t2 = t * t;
  return t2 * t2 * (4.0 * s + 1.0);
}

// dW/dr / r, the factor that turns a separation d (|d| = r) into grad W = d * factor:
//   kernelNorm * (-5 q (1 - q/2)^3) / (h r) = gradNorm * (1 - q/2)^3,  gradNorm = -5 kernelNorm / h^2.
// No division by r, so a coincident pair gets grad W = 0; (1 - q/2) is clamped at 0, so any r
// beyond the support (2h) gets 0 as well. invH = 1 / h.
float hemo_kernel_grad_norm(float h, float kernelNorm) {
  const float invH = 1.0 / h;
  return -5.0 * kernelNorm * invH * invH;
}

float hemo_kernel_grad_factor(float r, float invH, float gradNorm) {
  const float t = max(1.0 - 0.5 * r * invH, 0.0);
  return gradNorm * t * t * t;
}

// The same over gradNorm, (1 - q/2)^3 clamped at 0, for sums that apply gradNorm once at the
// end; halfInvH = 1 / 2h.
float hemo_kernel_grad_shape(float r, float halfInvH) {
  const float t = max(1.0 - r * halfInvH, 0.0);
  return t * t * t;
}

// The same, and 0 everywhere when `live` (1 or 0) is 0, as hemo_kernel_w_shape_live.
float hemo_kernel_grad_shape_live(float r, float halfInvH, float live) {
  const float t = max(live - r * halfInvH, 0.0);
  return t * t * t;
}
