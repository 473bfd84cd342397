"""The backward pass of the learned family's CNN: loss, crops forward, gradients (numpy).

The network and its forward pass are :mod:`sensorless.thresholds._cnn`;
training (:mod:`.training`) needs in addition the Gaussian negative
log-likelihood of the residual and its gradient with respect to every trained
array, written out by hand (checked against finite differences in the tests),
so that training needs no framework and the same seed gives the same weights.
"""

from __future__ import annotations

import numpy as np

from .._validation import FloatArray
from ..thresholds._cnn import Network, _normalised, _softplus, _taps

__all__ = ["forward_crops", "gradients", "loss_terms"]


def loss_terms(
    centre: FloatArray, spread: FloatArray, target: FloatArray, floor: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Gaussian negative log-likelihood per sample and its derivatives (normalised units).

    With w = softplus(spread) + floor: ℓ = log w + (target - centre)²/(2 w²).
    Returns ℓ, ∂ℓ/∂centre and ∂ℓ/∂spread.
    """
    width = _softplus(spread) + floor
    error = target - centre
    z2 = (error / width) ** 2
    nll = np.log(width) + 0.5 * z2
    d_centre = -error / width**2
    d_width = (1.0 - z2) / width
    sigmoid = 0.5 * (1.0 + np.tanh(0.5 * spread))
    return nll, d_centre, d_width * sigmoid


def forward_crops(net: Network, x: FloatArray) -> tuple[FloatArray, list[FloatArray]]:
    """Head output (n_crops, n_out, 2, n_dof) of crops (n_crops, n_steps, 4, n_dof); activations.

    Output i is the sample ``receptive_field - 1 + i`` of its crop.
    """
    a = _normalised(net, x)
    activations = [a]
    for k, (d, e) in enumerate(zip(net.dilations, net.delays, strict=True)):
        n = a.shape[1] - 2 * d - e
        a = np.tanh(net.kernels[k] @ _taps(a, d, n, 1) + net.biases[k])
        activations.append(a)
    return net.head @ a + net.head_bias, activations


def gradients(
    net: Network, x: FloatArray, target: FloatArray, weight: FloatArray
) -> tuple[float, list[FloatArray]]:
    """Weighted mean negative log-likelihood of crops and its gradient (training).

    Parameters
    ----------
    net : Network
    x : ndarray of shape (n_crops, n_steps, 4, n_dof)
        Input crops in their units; each gives outputs for its last
        ``n_steps - receptive_field + 1`` samples (no state before it).
    target : ndarray of shape (n_crops, n_out, n_dof)
        Residuals [N m] at those samples.
    weight : ndarray of shape (n_crops, n_out, n_dof)
        Weight of each sample in the loss (0: not used, e.g. during a contact).

    Returns
    -------
    loss : float
    grads : list of ndarray
        In the order of :meth:`Network.parameters`.
    """
    out, activations = forward_crops(net, x)
    t_norm = (target - net.output_mean) / net.output_scale
    nll, d_c, d_s = loss_terms(out[:, :, 0], out[:, :, 1], t_norm, net.floor)
    scale = 1.0 / max(float(weight.sum()), 1.0)
    d_out = np.stack((d_c, d_s), axis=2) * (weight * scale)[:, :, None]
    a = activations[-1]
    grads_head = _sum_outer(d_out, a)
    grads_head_bias = d_out.sum(axis=(0, 1, 3))[:, None]
    da = np.swapaxes(net.head, 0, 1) @ d_out
    kernel_grads: list[FloatArray] = []
    bias_grads: list[FloatArray] = []
    for k in reversed(range(len(net.dilations))):
        d, below = net.dilations[k], activations[k]
        du = da * (1.0 - activations[k + 1] ** 2)
        n = du.shape[1]
        kernel_grads.insert(0, _sum_outer(du, _taps(below, d, n, 1)))
        per_joint = net.biases[k].shape[1] > 1
        bias_grads.insert(0, du.sum(axis=(0, 1)) if per_joint else du.sum(axis=(0, 1, 3))[:, None])
        if k == 0:
            break
        d_taps = np.swapaxes(net.kernels[k], 0, 1) @ du
        c = below.shape[2]
        da = np.zeros_like(below)
        da[:, 2 * d : 2 * d + n] += d_taps[:, :, :c]
        da[:, d : d + n] += d_taps[:, :, c : 2 * c]
        da[:, :n] += d_taps[:, :, 2 * c :]
    loss = float((nll * weight).sum() * scale)
    return loss, [*kernel_grads, *bias_grads, grads_head, grads_head_bias]


def _sum_outer(du: FloatArray, a: FloatArray) -> FloatArray:
    """Σ over crops, samples and joints of du (.., o, n) ⊗ a (.., i, n) → (o, i)."""
    o, i = du.shape[2], a.shape[2]
    left = np.moveaxis(du, 2, 0).reshape(o, -1)
    right = np.moveaxis(a, 2, 0).reshape(i, -1)
    return np.asarray(left @ right.T)
