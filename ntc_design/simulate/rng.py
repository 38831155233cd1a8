"""Normals for Monte Carlo, drawn in compiled code: one xoshiro256** stream per path and
the ziggurat method.

**Streams.** Block b of a run (:mod:`.montecarlo`) seeds its p paths from
``SeedSequence(seed, spawn_key=(b,)).generate_state(4·p, uint64)``: path q of the block
takes words 4q … 4q+3 as its xoshiro256** state (an all-zero state, probability 2⁻²⁵⁶, is
replaced by a fixed non-zero one). A path draws its normals in step order, 2·E per step
(E additive, then E multiplicative, as the NumPy stream is laid out), so a path's noise
depends only on (seed, block_paths, its index): not on the tile of paths the kernel
integrates together, the batch of steps, the workers or the machine.

**Generator.** xoshiro256** (Blackman & Vigna, "Scrambled linear pseudorandom number
generators", ACM TOMS 47(4), 2021): 256 bits of state, period 2²⁵⁶ − 1, passes BigCrush;
one 64-bit word is a few integer operations. Paths' streams start at independent
SeedSequence outputs (overlap probability for 10⁹ paths of 10¹² draws: < 2⁻¹⁵⁰).

The compiled code (the generator, the ziggurat, the fused kernel) is in
:mod:`.kernels`, one file, so that Numba's cache of the kernel is rebuilt whenever any of
it changes.

**Normals.** The ziggurat (Marsaglia & Tsang, "The ziggurat method for generating random
variables", J. Stat. Softw. 5(8), 2000) in Doornik's formulation ("An improved ziggurat
method to generate normal random samples", 2005), with 1024 layers instead of his 128: one
64-bit word gives the layer (its low 10 bits) and a 53-bit uniform u in [-1, 1) (its high
bits); z = u·x_i is accepted at once when |u| < x_{i+1}/x_i, which fails for 0.43 % of
words (2.8 % with 128 layers). The fast test has no branch and vectorises across paths; the
rare failures go to the wedge test or, in the base layer, to the tail beyond R by
Marsaglia's exponential method, with further words of the same stream. The ``numpy``
generator (``rng: numpy``) keeps NumPy's PCG64 streams for who needs them.
"""

from __future__ import annotations

import numpy as np

GENERATORS = ("xoshiro", "numpy")

LAYERS = 1024
# R (the base layer's edge) and V (every layer's area), solved to 25 digits so that the
# layers close at 0: Σ-construction x_1 = R, x_{i+1} = f⁻¹(V/x_i + f(x_i)), f(0) reached
# at layer 1023 exactly (f(x) = exp(−x²/2)).
_R = "4.038849846109504522714423"
_V = "0.001226324646353088072885371"


def _tables(digits: int = 40) -> list:
    """The layer edges x_0 … x_1024 in ``digits``-digit arithmetic (mpmath): x_0 = V/f(R)
    (the base layer with its tail has area V), x_1 = R, then equal-area layers down to
    x_1024 = 0. :data:`ZIG_X` is this rounded to the nearest doubles; a test checks it
    bit for bit, and that the top layer closes at f(0) = 1.

    Parameters
    ----------
    digits : int
        Working precision.

    Returns
    -------
    list
        1025 mpmath numbers, and last the residual V/x_1023 + f(x_1023) − 1.
    """
    from mpmath import mp, mpf  # sympy's dependency; only for this check

    with mp.workdps(digits):
        r, v = mpf(_R), mpf(_V)
        x = [v / mp.exp(-r * r / 2), r]
        for _ in range(2, LAYERS):
            x.append(mp.sqrt(-2 * mp.log(v / x[-1] + mp.exp(-(x[-1] ** 2) / 2))))
        residual = v / x[-1] + mp.exp(-(x[-1] ** 2) / 2) - 1
        return [*x, mpf(0), residual]


# The layer edges as exact binary values (the nearest doubles to _tables()): the normals do
# not depend on a platform's last-bit differences in exp and log.
ZIG_X = np.array(
    [float.fromhex(h) for h in (
        "0x1.118020ba8384fp+2", "0x1.027c84109fad5p+2", "0x1.ed917eb8389ccp+1",
        "0x1.df0df33c82a26p+1", "0x1.d4678846623afp+1", "0x1.cbf02c81463dap+1",
        "0x1.c4e20525be0bcp+1", "0x1.bed13c3f86eaap+1", "0x1.b97c669671246p+1",
        "0x1.b4b8c3eb841e8p+1", "0x1.b068d0fb2ebf7p+1", "0x1.ac774d46060efp+1",
        "0x1.a8d465a696327p+1", "0x1.a573fe23beac3p+1", "0x1.a24c9c526a58ep+1",
        "0x1.9f56b0622d2e1p+1", "0x1.9c8c18808fccdp+1", "0x1.99e7c98d0abadp+1",
        "0x1.97659070e3792p+1", "0x1.9501e430a386fp+1", "0x1.92b9c39e9d6f4p+1",
        "0x1.908a9b4fdb0b1p+1", "0x1.8e72318b61bd4p+1", "0x1.8c6e969fec5cep+1",
        "0x1.8a7e188383122p+1", "0x1.889f38f0f5ef4p+1", "0x1.86d0a56ec05e1p+1",
        "0x1.851130d1bad30p+1", "0x1.835fcde9a647dp+1", "0x1.81bb8b198f502p+1",
        "0x1.80238eac9ac95p+1", "0x1.7e9713c296ff0p+1", "0x1.7d1567b7bd508p+1",
        "0x1.7b9de7f1293e4p+1", "0x1.7a2ffffc30e1bp+1", "0x1.78cb27f25ff57p+1",
        "0x1.776ee3169eb6dp+1", "0x1.761abea23b404p+1", "0x1.74ce50ba4367bp+1",
        "0x1.73893786fa0cep+1", "0x1.724b186849902p+1", "0x1.71139f42f560ap+1",
        "0x1.6fe27de301e7cp+1", "0x1.6eb76b705d995p+1", "0x1.6d9223f34e8d1p+1",
        "0x1.6c7267e68b236p+1", "0x1.6b57fbd5360c5p+1", "0x1.6a42a80339eddp+1",
        "0x1.6932381eb96f0p+1", "0x1.68267af977c02p+1", "0x1.671f4249456e2p+1",
        "0x1.661c626e9ed12p+1", "0x1.651db240c5b84p+1", "0x1.64230adeb805cp+1",
        "0x1.632c4784796aep+1", "0x1.6239456437f60p+1", "0x1.6149e382e2286p+1",
        "0x1.605e0297d22ffp+1", "0x1.5f7584ef3d01ep+1", "0x1.5e904e4f1db05p+1",
        "0x1.5dae43de5daccp+1", "0x1.5ccf4c0e01e64p+1", "0x1.5bf34e842b027p+1",
        "0x1.5b1a3408bc740p+1", "0x1.5a43e67383028p+1", "0x1.5970509bb7936p+1",
        "0x1.589f5e48bebbap+1", "0x1.57d0fc2408e91p+1", "0x1.570517abf9d3ap+1",
        "0x1.563b9f27c079ap+1", "0x1.5574819c0b29bp+1", "0x1.54afaec08522dp+1",
        "0x1.53ed16f60d1b7p+1", "0x1.532cab3d95976p+1", "0x1.526e5d2fa1624p+1",
        "0x1.51b21ef44fc6ap+1", "0x1.50f7e33bed3f4p+1", "0x1.503f9d37fe631p+1",
        "0x1.4f894094bbb73p+1", "0x1.4ed4c172f5e53p+1", "0x1.4e2214625a90fp+1",
        "0x1.4d712e5c12b46p+1", "0x1.4cc204bdb4013p+1", "0x1.4c148d447f562p+1",
        "0x1.4b68be08e6d02p+1", "0x1.4abe8d7a56765p+1", "0x1.4a15f25b3ae31p+1",
        "0x1.496ee3bd41af7p+1", "0x1.48c958fdcfb81p+1", "0x1.482549c2a9a25p+1",
        "0x1.4782adf6cb50dp+1", "0x1.46e17dc76b355p+1", "0x1.4641b1a126aa3p+1",
        "0x1.45a3422d54b4fp+1", "0x1.4506284f7cc28p+1", "0x1.446a5d22ef1ecp+1",
        "0x1.43cfd9f87d0f3p+1", "0x1.433698544ea17p+1", "0x1.429e91ebd4601p+1",
        "0x1.4207c0a3d3413p+1", "0x1.41721e8e89401p+1", "0x1.40dda5e9e92dep+1",
        "0x1.404a511dec601p+1", "0x1.3fb81abaf8f90p+1", "0x1.3f26fd785b9d8p+1",
        "0x1.3e96f432d37f5p+1", "0x1.3e07f9eb2fb33p+1", "0x1.3d7a09c4fcdfbp+1",
        "0x1.3ced1f05425bep+1", "0x1.3c6135114de93p+1", "0x1.3bd6476d8d3c5p+1",
        "0x1.3b4c51bc749a0p+1", "0x1.3ac34fbd71d4cp+1", "0x1.3a3b3d4beb066p+1",
        "0x1.39b4165e48677p+1", "0x1.392dd70508b3bp+1", "0x1.38a87b69df8ecp+1",
        "0x1.3823ffcedd6a1p+1", "0x1.37a0608da06f3p+1", "0x1.371d9a168dfd3p+1",
        "0x1.369ba8f0144b2p+1", "0x1.361a89b5f3cb1p+1", "0x1.359a39188feb1p+1",
        "0x1.351ab3dc46db4p+1", "0x1.349bf6d8d0017p+1", "0x1.341dfef8a0ca1p+1",
        "0x1.33a0c93857892p+1", "0x1.332452a62c236p+1", "0x1.32a89861663a8p+1",
        "0x1.322d9799d89bcp+1", "0x1.31b34d8f61b3bp+1", "0x1.3139b79170cc6p+1",
        "0x1.30c0d2fe8fdfcp+1", "0x1.30489d43f1c91p+1", "0x1.2fd113dd04a48p+1",
        "0x1.2f5a3453082dap+1", "0x1.2ee3fc3ca7f06p+1", "0x1.2e6e693d9921dp+1",
        "0x1.2df979063bf8cp+1", "0x1.2d85295340606p+1", "0x1.2d1177ed4ddf9p+1",
        "0x1.2c9e62a8ae939p+1", "0x1.2c2be764fd1c4p+1", "0x1.2bba040cd55b5p+1",
        "0x1.2b48b69587e85p+1", "0x1.2ad7fcfed01d3p+1", "0x1.2a67d5528ca12p+1",
        "0x1.29f83da47a565p+1", "0x1.29893411f1944p+1", "0x1.291ab6c1a5957p+1",
        "0x1.28acc3e366034p+1", "0x1.283f59afe28a4p+1", "0x1.27d276687062cp+1",
        "0x1.27661856d1ba7p+1", "0x1.26fa3dccfeec6p+1", "0x1.268ee524f1759p+1",
        "0x1.26240cc07095cp+1", "0x1.25b9b308df8b5p+1", "0x1.254fd66f0d5c5p+1",
        "0x1.24e6756b061c3p+1", "0x1.247d8e7be5a18p+1", "0x1.24152027ab9d6p+1",
        "0x1.23ad28fb11077p+1", "0x1.2345a7895ed36p+1", "0x1.22de9a6c45e1fp+1",
        "0x1.22780043b8244p+1", "0x1.2211d7b5c2e55p+1", "0x1.21ac1f6e6a2f0p+1",
        "0x1.2146d61f85420p+1", "0x1.20e1fa809c153p+1", "0x1.207d8b4ec5d50p+1",
        "0x1.2019874c8858bp+1", "0x1.1fb5ed41b8859p+1", "0x1.1f52bbfb5b980p+1",
        "0x1.1eeff24b894a9p+1", "0x1.1e8d8f094ed31p+1", "0x1.1e2b911092af9p+1",
        "0x1.1dc9f741f93abp+1", "0x1.1d68c082ca02bp+1", "0x1.1d07ebbcd5dabp+1",
        "0x1.1ca777de5da1bp+1", "0x1.1c4763d9f9b89p+1", "0x1.1be7aea682212p+1",
        "0x1.1b88573ef741cp+1", "0x1.1b295ca26b475p+1", "0x1.1acabdd3ec20cp+1",
        "0x1.1a6c79da6e0fap+1", "0x1.1a0e8fc0b6c88p+1", "0x1.19b0fe95491eep+1",
        "0x1.1953c56a51380p+1", "0x1.18f6e35591414p+1", "0x1.189a57704ea4cp+1",
        "0x1.183e20d73fb92p+1", "0x1.17e23eaa79e89p+1", "0x1.1786b00d604b4p+1",
        "0x1.172b742692b24p+1", "0x1.16d08a1fdd1e6p+1", "0x1.1675f12627a11p+1",
        "0x1.161ba86966a35p+1", "0x1.15c1af1c8b8fap+1", "0x1.1568047575dcap+1",
        "0x1.150ea7ace474cp+1", "0x1.14b597fe67790p+1", "0x1.145cd4a8525b6p+1",
        "0x1.14045cebae4f2p+1", "0x1.13ac300c2d0c0p+1", "0x1.13544d501be1fp+1",
        "0x1.12fcb400571b9p+1", "0x1.12a563683dac4p+1", "0x1.124e5ad5a528ap+1",
        "0x1.11f79998ce06ep+1", "0x1.11a11f0458249p+1", "0x1.114aea6d3790ep+1",
        "0x1.10f4fb2aa998dp+1", "0x1.109f50962a133p+1", "0x1.1049ea0b68eb9p+1",
        "0x1.0ff4c6e83fe9cp+1", "0x1.0f9fe68ca8b45p+1", "0x1.0f4b485ab30ccp+1",
        "0x1.0ef6ebb67b436p+1", "0x1.0ea2d00620e1cp+1", "0x1.0e4ef4b1bd8a4p+1",
        "0x1.0dfb59235c0aep+1", "0x1.0da7fcc6efa29p+1", "0x1.0d54df0a4b76fp+1",
        "0x1.0d01ff5d1a3a5p+1", "0x1.0caf5d30d5ff7p+1", "0x1.0c5cf7f8c03a9p+1",
        "0x1.0c0acf29d9eeap+1", "0x1.0bb8e23adc051p+1", "0x1.0b6730a42fcfap+1",
        "0x1.0b15b9dfe7b26p+1", "0x1.0ac47d69b7f5bp+1", "0x1.0a737abeefbf0p+1",
        "0x1.0a22b15e722eap+1", "0x1.09d220c8afa30p+1", "0x1.0981c87f9f1f0p+1",
        "0x1.0931a806b7d3ap+1", "0x1.08e1bee2eacbbp+1", "0x1.08920c9a9cb85p+1",
        "0x1.084290b59fde0p+1", "0x1.07f34abd2e219p+1", "0x1.07a43a3be3336p+1",
        "0x1.07555ebdb6d8ep+1", "0x1.0706b7cff7537p+1", "0x1.06b8450143e3bp+1",
        "0x1.066a05e187691p+1", "0x1.061bfa01f31c3p+1", "0x1.05ce20f4f9644p+1",
        "0x1.05807a4e48c61p+1", "0x1.053305a2c6eccp+1", "0x1.04e5c2888bcaep+1",
        "0x1.0498b096dcd40p+1", "0x1.044bcf66284dep+1", "0x1.03ff1e9000b88p+1",
        "0x1.03b29daf184cep+1", "0x1.03664c5f3c91ap+1", "0x1.031a2a3d52056p+1",
        "0x1.02ce36e74fddep+1", "0x1.028271fc3bdbap+1", "0x1.0236db1c26321p+1",
        "0x1.01eb71e82582bp+1", "0x1.01a0360252ebdp+1", "0x1.0155270dc629dp+1",
        "0x1.010a44ae91caep+1", "0x1.00bf8e89bf749p+1", "0x1.007504454c3aep+1",
        "0x1.002aa58825087p+1", "0x1.ffc0e3f4462efp+0", "0x1.ff2cd28810f66p+0",
        "0x1.fe99161ef9720p+0", "0x1.fe05ae0e12e36p+0", "0x1.fd7299ac2e336p+0",
        "0x1.fcdfd851d380dp+0", "0x1.fc4d69593bcc8p+0", "0x1.fbbb4c1e4ac23p+0",
        "0x1.fb297ffe889d2p+0", "0x1.fa9804591c289p+0", "0x1.fa06d88ec4db1p+0",
        "0x1.f975fc01d50c1p+0", "0x1.f8e56e162c435p+0", "0x1.f8552e3131a14p+0",
        "0x1.f7c53bb9ce60ep+0", "0x1.f73596186870cp+0", "0x1.f6a63cb6dd24cp+0",
        "0x1.f6172f007bfe1p+0", "0x1.f5886c62018acp+0", "0x1.f4f9f449925adp+0",
        "0x1.f46bc626b60bdp+0", "0x1.f3dde16a52691p+0", "0x1.f3504586a6a18p+0",
        "0x1.f2c2f1ef46913p+0", "0x1.f235e619161ffp+0", "0x1.f1a9217a44b28p+0",
        "0x1.f11ca38a48affp+0", "0x1.f0906bc1db195p+0", "0x1.f004799af3342p+0",
        "0x1.ef78cc90c246dp+0", "0x1.eeed641faf673p+0", "0x1.ee623fc55359fp+0",
        "0x1.edd75f007483ap+0", "0x1.ed4cc15102ea3p+0", "0x1.ecc266381446fp+0",
        "0x1.ec384d37e0288p+0", "0x1.ebae75d3bc24ep+0", "0x1.eb24df90181acp+0",
        "0x1.ea9b89f27a81bp+0", "0x1.ea1274817cca1p+0", "0x1.e9899ec4c7ca9p+0",
        "0x1.e9010845103cbp+0", "0x1.e878b08c13474p+0", "0x1.e7f0972493164p+0",
        "0x1.e768bb9a53809p+0", "0x1.e6e11d7a16bb0p+0", "0x1.e659bc519a182p+0",
        "0x1.e5d297af92d4cp+0", "0x1.e54baf23aaf17p+0", "0x1.e4c5023e7e17cp+0",
        "0x1.e43e9091968bdp+0", "0x1.e3b859af6a29ep+0", "0x1.e3325d2b576f0p+0",
        "0x1.e2ac9a99a28dbp+0", "0x1.e227118f728d5p+0", "0x1.e1a1c1a2ce74dp+0",
        "0x1.e11caa6a9a7fdp+0", "0x1.e097cb7e955efp+0", "0x1.e01324775581ap+0",
        "0x1.df8eb4ee466b3p+0", "0x1.df0a7c7da610dp+0", "0x1.de867ac082428p+0",
        "0x1.de02af52b61c9p+0", "0x1.dd7f19d0e7839p+0", "0x1.dcfbb9d884a90p+0",
        "0x1.dc788f07c1994p+0", "0x1.dbf598fd95d2cp+0", "0x1.db72d759b9e57p+0",
        "0x1.daf049bca51bbp+0", "0x1.da6defc78b2afp+0", "0x1.d9ebc91c59ed3p+0",
        "0x1.d969d55db722cp+0", "0x1.d8e8142efe3bap+0", "0x1.d86685343e292p+0",
        "0x1.d7e528123737ap+0", "0x1.d763fc6e58ef2p+0", "0x1.d6e301eebffc3p+0",
        "0x1.d662383a341fbp+0", "0x1.d5e19ef826263p+0", "0x1.d56135d0ade66p+0",
        "0x1.d4e0fc6c88465p+0", "0x1.d460f2751547cp+0", "0x1.d3e11794561b9p+0",
        "0x1.d3616b74eb3b0p+0", "0x1.d2e1edc212887p+0", "0x1.d2629e27a575ep+0",
        "0x1.d1e37c5217323p+0", "0x1.d16487ee72dc5p+0", "0x1.d0e5c0aa59bcfp+0",
        "0x1.d067263401859p+0", "0x1.cfe8b83a32965p+0", "0x1.cf6a766c4648fp+0",
        "0x1.ceec607a2541cp+0", "0x1.ce6e761445c60p+0", "0x1.cdf0b6ebaa188p+0",
        "0x1.cd7322b1deda7p+0", "0x1.ccf5b918f972fp+0", "0x1.cc7879d3967aap+0",
        "0x1.cbfb6494d82d7p+0", "0x1.cb7e791064e0bp+0", "0x1.cb01b6fa657e9p+0",
        "0x1.ca851e078406cp+0", "0x1.ca08adecea132p+0", "0x1.c98c66603f623p+0",
        "0x1.c9104717a8657p+0", "0x1.c8944fc9c4d4cp+0", "0x1.c818802dae463p+0",
        "0x1.c79cd7faf6ca1p+0", "0x1.c72156e9a78c1p+0", "0x1.c6a5fcb23f77ap+0",
        "0x1.c62ac90db1e1bp+0", "0x1.c5afbbb56535dp+0", "0x1.c534d46331a80p+0",
        "0x1.c4ba12d15fe9fp+0", "0x1.c43f76baa7e4dp+0", "0x1.c3c4ffda2f76cp+0",
        "0x1.c34aadeb89343p+0", "0x1.c2d080aab32d1p+0", "0x1.c25677d415b5ap+0",
        "0x1.c1dc932482335p+0", "0x1.c162d25931ec7p+0", "0x1.c0e9352fc4dc9p+0",
        "0x1.c06fbb66408b3p+0", "0x1.bff664bb0ee72p+0", "0x1.bf7d30ecfd241p+0",
        "0x1.bf041fbb3a9c7p+0", "0x1.be8b30e557b60p+0", "0x1.be12642b44c9ep+0",
        "0x1.bd99b94d51100p+0", "0x1.bd21300c298d2p+0", "0x1.bca8c828d8048p+0",
        "0x1.bc308164c1ec6p+0", "0x1.bbb85b81a7654p+0", "0x1.bb405641a234cp+0",
        "0x1.bac8716724c2ap+0", "0x1.ba50acb4f9190p+0", "0x1.b9d907ee3fe79p+0",
        "0x1.b96182d66f895p+0", "0x1.b8ea1d31530d0p+0", "0x1.b872d6c309407p+0",
        "0x1.b7fbaf5003be6p+0", "0x1.b784a69d05fefp+0", "0x1.b70dbc6f246aap+0",
        "0x1.b696f08bc3700p+0", "0x1.b62042b8969bap+0", "0x1.b5a9b2bb9fb2cp+0",
        "0x1.b533405b2dcfdp+0", "0x1.b4bceb5ddc825p+0", "0x1.b446b38a92effp+0",
        "0x1.b3d098a882f8cp+0", "0x1.b35a9a7f285d7p+0", "0x1.b2e4b8d647e78p+0",
        "0x1.b26ef375ee941p+0", "0x1.b1f94a2670c0bp+0", "0x1.b183bcb0695a3p+0",
        "0x1.b10e4adcb90dap+0", "0x1.b098f474857bap+0", "0x1.b023b941386d4p+0",
        "0x1.afae990c7f0b5p+0", "0x1.af3993a049176p+0", "0x1.aec4a8c6c826dp+0",
        "0x1.ae4fd84a6edfcp+0", "0x1.addb21f5f0380p+0", "0x1.ad6685943eb5cp+0",
        "0x1.acf202f08bb1dp+0", "0x1.ac7d99d6469c7p+0", "0x1.ac094a111c42fp+0",
        "0x1.ab95136cf617dp+0", "0x1.ab20f5b5f97c4p+0", "0x1.aaacf0b8870b4p+0",
        "0x1.aa39044139e6ap+0", "0x1.a9c5301ce7059p+0", "0x1.a95174189c84cp+0",
        "0x1.a8ddd001a0f81p+0", "0x1.a86a43a572be0p+0", "0x1.a7f6ced1c7547p+0",
        "0x1.a78371548aaefp+0", "0x1.a7102afbde8ecp+0", "0x1.a69cfb9619dc1p+0",
        "0x1.a629e2f1c800cp+0", "0x1.a5b6e0dda8448p+0", "0x1.a543f528ad2a9p+0",
        "0x1.a4d11fa1fbd09p+0", "0x1.a45e6018eb4efp+0", "0x1.a3ebb65d041a7p+0",
        "0x1.a379223dff674p+0", "0x1.a306a38bc68d4p+0", "0x1.a2943a16726d5p+0",
        "0x1.a221e5ae4ad87p+0", "0x1.a1afa623c5f78p+0", "0x1.a13d7b4787b48p+0",
        "0x1.a0cb64ea61253p+0", "0x1.a05962dd4ff66p+0", "0x1.9fe774f17dd8ep+0",
        "0x1.9f759af83fef3p+0", "0x1.9f03d4c3163cbp+0", "0x1.9e922223ab15bp+0",
        "0x1.9e2082ebd2906p+0", "0x1.9daef6ed89f76p+0", "0x1.9d3d7dfaf73cbp+0",
        "0x1.9ccc17e6686e3p+0", "0x1.9c5ac482532b0p+0", "0x1.9be983a154197p+0",
        "0x1.9b7855162e5ebp+0", "0x1.9b0738b3cb16cp+0", "0x1.9a962e4d38cdbp+0",
        "0x1.9a2535b5aaf9cp+0", "0x1.99b44ec079763p+0", "0x1.994379411fff8p+0",
        "0x1.98d2b50b3dafep+0", "0x1.986201f2947ccp+0", "0x1.97f15fcb08b5bp+0",
        "0x1.9780ce68a0833p+0", "0x1.97104d9f83672p+0", "0x1.969fdd43f9bd9p+0",
        "0x1.962f7d2a6c3e6p+0", "0x1.95bf2d27637fcp+0", "0x1.954eed0f87796p+0",
        "0x1.94debcb79f087p+0", "0x1.946e9bf48f745p+0", "0x1.93fe8a9b5bf3ep+0",
        "0x1.938e888125339p+0", "0x1.931e957b28dc5p+0", "0x1.92aeb15ec11adp+0",
        "0x1.923edc016427cp+0", "0x1.91cf1538a3d05p+0", "0x1.915f5cda2cffdp+0",
        "0x1.90efb2bbc7499p+0", "0x1.908016b354736p+0", "0x1.90108896d000ep+0",
        "0x1.8fa1083c4ebf2p+0", "0x1.8f319579fe50ep+0", "0x1.8ec2302624bbcp+0",
        "0x1.8e52d8171ff54p+0", "0x1.8de38d236570ep+0", "0x1.8d744f2181ae7p+0",
        "0x1.8d051de817c93p+0", "0x1.8c95f94de1070p+0", "0x1.8c26e129ac688p+0",
        "0x1.8bb7d5525e393p+0", "0x1.8b48d59eefa07p+0", "0x1.8ad9e1e66e328p+0",
        "0x1.8a6af9fffb827p+0", "0x1.89fc1dc2ccb43p+0", "0x1.898d4d062a0eep+0",
        "0x1.891e87a16e8fap+0", "0x1.88afcd6c077d5p+0", "0x1.88411e3d73fb8p+0",
        "0x1.87d279ed449f2p+0", "0x1.8763e0531b023p+0", "0x1.86f55146a958ep+0",
        "0x1.8686cc9fb2066p+0", "0x1.8618523607320p+0", "0x1.85a9e1e18a5d3p+0",
        "0x1.853b7b7a2bf8fp+0", "0x1.84cd1ed7eafc6p+0", "0x1.845ecbd2d47adp+0",
        "0x1.83f08243033abp+0", "0x1.838242009f4c6p+0", "0x1.83140ae3dda15p+0",
        "0x1.82a5dcc4ffa37p+0", "0x1.8237b77c52ccep+0", "0x1.81c99ae2303f6p+0",
        "0x1.815b86cefc5cbp+0", "0x1.80ed7b1b265e8p+0", "0x1.807f779f27eeep+0",
        "0x1.80117c3384c06p+0", "0x1.7fa388b0ca275p+0", "0x1.7f359cef8eb1ep+0",
        "0x1.7ec7b8c871c16p+0", "0x1.7e59dc141b232p+0", "0x1.7dec06ab3aa98p+0",
        "0x1.7d7e386687c52p+0", "0x1.7d10711ec11e3p+0", "0x1.7ca2b0acac2dcp+0",
        "0x1.7c34f6e914d72p+0", "0x1.7bc743accd013p+0", "0x1.7b5996d0ac303p+0",
        "0x1.7aebf02d8f1edp+0", "0x1.7a7e4f9c5757fp+0", "0x1.7a10b4f5ead05p+0",
        "0x1.79a32013337fap+0", "0x1.793590cd1efa5p+0", "0x1.78c806fc9e0b1p+0",
        "0x1.785a827aa44c0p+0", "0x1.77ed032027c04p+0", "0x1.777f88c6206d2p+0",
        "0x1.7712134587f37p+0", "0x1.76a4a2775928dp+0", "0x1.763736348fb05p+0",
        "0x1.75c9ce562793ep+0", "0x1.755c6ab51cdcep+0", "0x1.74ef0b2a6b2cep+0",
        "0x1.7481af8f0d565p+0", "0x1.741457bbfcf4cp+0", "0x1.73a7038a32056p+0",
        "0x1.7339b2d2a27edp+0", "0x1.72cc656e41e93p+0", "0x1.725f1b3600f5ep+0",
        "0x1.71f1d402cd170p+0", "0x1.71848fad90167p+0", "0x1.71174e0f2fad7p+0",
        "0x1.70aa0f008d1adp+0", "0x1.703cd25a84b9fp+0", "0x1.6fcf97f5ed98fp+0",
        "0x1.6f625fab990e8p+0", "0x1.6ef52954524fep+0", "0x1.6e87f4c8de065p+0",
        "0x1.6e1ac1e1f9e3dp+0", "0x1.6dad90785c387p+0", "0x1.6d406064b3864p+0",
        "0x1.6cd3317fa615ep+0", "0x1.6c6603a1d189fp+0", "0x1.6bf8d6a3ca726p+0",
        "0x1.6b8baa5e1bdfep+0", "0x1.6b1e7ea946f5dp+0", "0x1.6ab1535dc27d0p+0",
        "0x1.6a442853fa750p+0", "0x1.69d6fd644fa59p+0", "0x1.6969d267172fbp+0",
        "0x1.68fca7349a1dap+0", "0x1.688f7ba514f31p+0", "0x1.68224f90b73c7p+0",
        "0x1.67b522cfa31dep+0", "0x1.6747f539ece17p+0", "0x1.66dac6a79a854p+0",
        "0x1.666d96f0a3488p+0", "0x1.660065ecef386p+0", "0x1.6593337456bc3p+0",
        "0x1.6525ff5ea2210p+0", "0x1.64b8c98389245p+0", "0x1.644b91bab27efp+0",
        "0x1.63de57dbb36e3p+0", "0x1.63711bbe0f3d4p+0", "0x1.6303dd3936cd8p+0",
        "0x1.62969c24881e5p+0", "0x1.622958574dd3fp+0", "0x1.61bc11a8bebdcp+0",
        "0x1.614ec7effd5c5p+0", "0x1.60e17b0417658p+0", "0x1.60742abc05494p+0",
        "0x1.6006d6eea9b48p+0", "0x1.5f997f72d113bp+0", "0x1.5f2c241f3114bp+0",
        "0x1.5ebec4ca68278p+0", "0x1.5e51614afcfe6p+0", "0x1.5de3f9775e0cfp+0",
        "0x1.5d768d25e1068p+0", "0x1.5d091c2cc25b7p+0", "0x1.5c9ba66224b5cp+0",
        "0x1.5c2e2b9c10748p+0", "0x1.5bc0abb073267p+0", "0x1.5b5326751f03bp+0",
        "0x1.5ae59bbfca666p+0", "0x1.5a780b660f422p+0", "0x1.5a0a753d6a9aep+0",
        "0x1.599cd91b3bfa2p+0", "0x1.592f36d4c4e3bp+0", "0x1.58c18e3f28490p+0",
        "0x1.5853df2f69fb5p+0", "0x1.57e6297a6e1cep+0", "0x1.57786cf4f890ep+0",
        "0x1.570aa973ac6a8p+0", "0x1.569cdecb0b5a3p+0", "0x1.562f0ccf751a5p+0",
        "0x1.55c1335526da2p+0", "0x1.555352303aa7fp+0", "0x1.54e56934a6d95p+0",
        "0x1.547778363d72ep+0", "0x1.54097f08ab8dap+0", "0x1.539b7d7f78bc4p+0",
        "0x1.532d736e066ddp+0", "0x1.52bf60a78f4fap+0", "0x1.525144ff26adep+0",
        "0x1.51e32047b7d25p+0", "0x1.5174f2540561bp+0", "0x1.5106baf6a8b7cp+0",
        "0x1.50987a0211419p+0", "0x1.502a2f4883d64p+0", "0x1.4fbbda9c1a0e3p+0",
        "0x1.4f4d7bcec198ap+0", "0x1.4edf12b23b8fcp+0", "0x1.4e709f181bca9p+0",
        "0x1.4e0220d1c82dcp+0", "0x1.4d9397b077fa3p+0", "0x1.4d250385331a2p+0",
        "0x1.4cb66420d16c7p+0", "0x1.4c47b953fa0dap+0", "0x1.4bd902ef229fcp+0",
        "0x1.4b6a40c28e8fbp+0", "0x1.4afb729e4e590p+0", "0x1.4a8c98523ec77p+0",
        "0x1.4a1db1ae0836bp+0", "0x1.49aebe811dd01p+0", "0x1.493fbe9abcc5ep+0",
        "0x1.48d0b1c9eb8d1p+0", "0x1.486197dd79147p+0", "0x1.47f270a3fbf9ap+0",
        "0x1.47833bebd1bc3p+0", "0x1.4713f9831dee2p+0", "0x1.46a4a937c9620p+0",
        "0x1.46354ad781574p+0", "0x1.45c5de2fb6a36p+0", "0x1.4556630d9cd96p+0",
        "0x1.44e6d93e296e6p+0", "0x1.4477408e12db7p+0", "0x1.440798c9cfbdbp+0",
        "0x1.4397e1bd95f2fp+0", "0x1.43281b3559b41p+0", "0x1.42b844fcccacbp+0",
        "0x1.42485edf5d102p+0", "0x1.41d868a834ab7p+0", "0x1.4168622237f4ap+0",
        "0x1.40f84b180516fp+0", "0x1.40882353f2fcap+0", "0x1.4017eaa01054ep+0",
        "0x1.3fa7a0c622977p+0", "0x1.3f37458fa5050p+0", "0x1.3ec6d8c5c7a3fp+0",
        "0x1.3e565a316e3a7p+0", "0x1.3de5c99b2f453p+0", "0x1.3d7526cb52ea5p+0",
        "0x1.3d047189d1e98p+0", "0x1.3c93a99e54888p+0", "0x1.3c22ced0317bap+0",
        "0x1.3bb1e0e66ccbbp+0", "0x1.3b40dfa7b6b70p+0", "0x1.3acfcada6a8fep+0",
        "0x1.3a5ea2448d96ap+0", "0x1.39ed65abcdcfep+0", "0x1.397c14d580d70p+0",
        "0x1.390aaf86a2acap+0", "0x1.38993583d4810p+0", "0x1.3827a6915b7a2p+0",
        "0x1.37b602731f760p+0", "0x1.374448eca9c84p+0", "0x1.36d279c123f37p+0",
        "0x1.366094b3565e4p+0", "0x1.35ee9985a7039p+0", "0x1.357c87fa181e8p+0",
        "0x1.350a5fd246d18p+0", "0x1.349820cf69c87p+0", "0x1.3425cab24fd66p+0",
        "0x1.33b35d3b5e8dbp+0", "0x1.3340d82a90d3cp+0", "0x1.32ce3b3f756f2p+0",
        "0x1.325b86392d906p+0", "0x1.31e8b8d66b560p+0", "0x1.3175d2d5704a8p+0",
        "0x1.3102d3f40bdd0p+0", "0x1.308fbbef99d46p+0", "0x1.301c8a8500bc4p+0",
        "0x1.2fa93f70b04cbp+0", "0x1.2f35da6e9fcb0p+0", "0x1.2ec25b3a4c65bp+0",
        "0x1.2e4ec18eb788dp+0", "0x1.2ddb0d26652d3p+0", "0x1.2d673dbb5a203p+0",
        "0x1.2cf353071a45bp+0", "0x1.2c7f4cc2a6d2dp+0", "0x1.2c0b2aa67c81ep+0",
        "0x1.2b96ec6a91bfcp+0", "0x1.2b2291c654d18p+0", "0x1.2aae1a70a9f35p+0",
        "0x1.2a39861fe96f8p+0", "0x1.29c4d489ddae7p+0", "0x1.29500563c13e9p+0",
        "0x1.28db18623cd45p+0", "0x1.28660d396542ap+0", "0x1.27f0e39cb96aap+0",
        "0x1.277b9b3f20233p+0", "0x1.270633d2e6188p+0", "0x1.2690ad09bba1fp+0",
        "0x1.261b0694b2902p+0", "0x1.25a540243bf13p+0", "0x1.252f596825cc3p+0",
        "0x1.24b9520f98d31p+0", "0x1.244329c9160afp+0", "0x1.23cce042746a8p+0",
        "0x1.23567528de6ecp+0", "0x1.22dfe828cfa53p+0", "0x1.226938ee122b9p+0",
        "0x1.21f26723bc255p+0", "0x1.217b72742d25fp+0", "0x1.21045a890b8fep+0",
        "0x1.208d1f0b41e92p+0", "0x1.2015bfa2fc22fp+0", "0x1.1f9e3bf7a4d6dp+0",
        "0x1.1f2693afe276ep+0", "0x1.1eaec6719471fp+0", "0x1.1e36d3e1d04b6p+0",
        "0x1.1dbebba4dea57p+0", "0x1.1d467d5e383f3p+0", "0x1.1cce18b082e45p+0",
        "0x1.1c558d3d8e4ffp+0", "0x1.1bdcdaa65100cp+0", "0x1.1b64008ae4ff5p+0",
        "0x1.1aeafe8a84956p+0", "0x1.1a71d44386f64p+0", "0x1.19f881535cd87p+0",
        "0x1.197f05568cfebp+0", "0x1.19055fe8b0b1dp+0", "0x1.188b90a4702a0p+0",
        "0x1.181197237ee72p+0", "0x1.179772fe97f84p+0", "0x1.171d23cd7a31ap+0",
        "0x1.16a2a926e450ap+0", "0x1.162802a0910dcp+0", "0x1.15ad2fcf331b7p+0",
        "0x1.1532304671120p+0", "0x1.14b70398e1485p+0", "0x1.143ba9580597cp+0",
        "0x1.13c02114470c3p+0", "0x1.13446a5cf17ebp+0", "0x1.12c884c02f1b2p+0",
        "0x1.124c6fcb03cf4p+0", "0x1.11d02b0948a3bp+0", "0x1.1153b605a6fdep+0",
        "0x1.10d7104993ca0p+0", "0x1.105a395d4a8d7p+0", "0x1.0fdd30c7c85fdp+0",
        "0x1.0f5ff60ec6cb0p+0", "0x1.0ee288b6b6917p+0", "0x1.0e64e842ba594p+0",
        "0x1.0de71434a13cdp+0", "0x1.0d690c0ce13ebp+0", "0x1.0ceacf4a91a1bp+0",
        "0x1.0c6c5d6b65231p+0", "0x1.0bedb5eba416fp+0", "0x1.0b6ed84626660p+0",
        "0x1.0aefc3f44d6b5p+0", "0x1.0a70786dfdb23p+0", "0x1.09f0f52998928p+0",
        "0x1.0971399bf5ab6p+0", "0x1.08f145385c3a6p+0", "0x1.087117707c4fap+0",
        "0x1.07f0afb467dccp+0", "0x1.07700d728b9e3p+0", "0x1.06ef3017a7de1p+0",
        "0x1.066e170ec90f0p+0", "0x1.05ecc1c1403efp+0", "0x1.056b2f969b5f4p+0",
        "0x1.04e95ff49d62dp+0", "0x1.0467523f362f9p+0", "0x1.03e505d87a62ep+0",
        "0x1.03627a209ae7dp+0", "0x1.02dfae75dc5d6p+0", "0x1.025ca2348e4c0p+0",
        "0x1.01d954b702288p+0", "0x1.0155c5558223cp+0", "0x1.00d1f36647c4bp+0",
        "0x1.004dde3d724c7p+0", "0x1.ff930a59f9c2dp-1", "0x1.fe89cf096903ap-1",
        "0x1.fd8009245b73ep-1", "0x1.fc75b741743c6p-1", "0x1.fb6ad7f2bb0bcp-1",
        "0x1.fa5f69c5860bep-1", "0x1.f9536b4263526p-1", "0x1.f846daed01c8ap-1",
        "0x1.f739b74419875p-1", "0x1.f62bfec153a1cp-1", "0x1.f51dafd9315c5p-1",
        "0x1.f40ec8faf2c9cp-1", "0x1.f2ff48907ccb1p-1", "0x1.f1ef2cfe3e6cep-1",
        "0x1.f0de74a3159e0p-1", "0x1.efcd1dd833397p-1", "0x1.eebb26f0fe5f8p-1",
        "0x1.eda88e3af7182p-1", "0x1.ec9551fd98388p-1", "0x1.eb81707a38874p-1",
        "0x1.ea6ce7ebeb186p-1", "0x1.e957b6875edabp-1", "0x1.e841da7abd514p-1",
        "0x1.e72b51ed8870ap-1", "0x1.e6141b00779b2p-1", "0x1.e4fc33cd53b27p-1",
        "0x1.e3e39a66d2396p-1", "0x1.e2ca4cd86f7cbp-1", "0x1.e1b0492647bb9p-1",
        "0x1.e0958d4cef474p-1", "0x1.df7a174149911p-1", "0x1.de5de4f05f1e9p-1",
        "0x1.dd40f43f32595p-1", "0x1.dc23430a9331cp-1", "0x1.db04cf26f18aap-1",
        "0x1.d9e596602e627p-1", "0x1.d8c596796bb03p-1", "0x1.d7a4cd2cdae87p-1",
        "0x1.d683382b8a1e1p-1", "0x1.d560d51d2fb3ap-1", "0x1.d43da19ff48fep-1",
        "0x1.d3199b483cc86p-1", "0x1.d1f4bfa06eb46p-1", "0x1.d0cf0c28b859ep-1",
        "0x1.cfa87e56d3259p-1", "0x1.ce811395c5de6p-1", "0x1.cd58c945a4c45p-1",
        "0x1.cc2f9cbb4fc96p-1", "0x1.cb058b402ed3ap-1", "0x1.c9da9211ebf57p-1",
        "0x1.c8aeae622b885p-1", "0x1.c781dd564217fp-1", "0x1.c6541c06e8067p-1",
        "0x1.c525677fead56p-1", "0x1.c3f5bcbfdbfccp-1", "0x1.c2c518b7bd36fp-1",
        "0x1.c193784aaa2a8p-1", "0x1.c060d84d7f562p-1", "0x1.bf2d35867e249p-1",
        "0x1.bdf88cacee0c1p-1", "0x1.bcc2da68ba9afp-1", "0x1.bb8c1b520e529p-1",
        "0x1.ba544bf0ea306p-1", "0x1.b91b68bcb9c23p-1", "0x1.b7e16e1be3a27p-1",
        "0x1.b6a658635636fp-1", "0x1.b56a23d6108a5p-1", "0x1.b42ccca4a717dp-1",
        "0x1.b2ee4eecc45d3p-1", "0x1.b1aea6b8a5068p-1", "0x1.b06dcffe8f82dp-1",
        "0x1.af2bc6a046d16p-1", "0x1.ade8866a78517p-1", "0x1.aca40b14245e7p-1",
        "0x1.ab5e503e017ddp-1", "0x1.aa175171d9e21p-1", "0x1.a8cf0a21e302ep-1",
        "0x1.a78575a80f05cp-1", "0x1.a63a8f4557b20p-1", "0x1.a4ee522102a2ep-1",
        "0x1.a3a0b947de6adp-1", "0x1.a251bfab7853ep-1", "0x1.a10160214a655p-1",
        "0x1.9faf9561e1529p-1", "0x1.9e5c5a07f9f10p-1", "0x1.9d07a88f95ce7p-1",
        "0x1.9bb17b55067a3p-1", "0x1.9a59cc93ef0efp-1", "0x1.990096663b81fp-1",
        "0x1.97a5d2c30d388p-1", "0x1.96497b7d9c5a4p-1", "0x1.94eb8a440d504p-1",
        "0x1.938bf89e39d7cp-1", "0x1.922abfec6d073p-1", "0x1.90c7d9661198bp-1",
        "0x1.8f633e1851c3fp-1", "0x1.8dfce6e4a7e61p-1", "0x1.8c94cc7f5f29ap-1",
        "0x1.8b2ae76e03546p-1", "0x1.89bf3005bed15p-1", "0x1.88519e69a601dp-1",
        "0x1.86e22a88eecc2p-1", "0x1.8570cc1d1350ap-1", "0x1.83fd7aa7de9a0p-1",
        "0x1.82882d71620a1p-1", "0x1.8110db85d22e4p-1", "0x1.7f977bb349916p-1",
        "0x1.7e1c04877005fp-1", "0x1.7c9e6c4d04c9ep-1", "0x1.7b1ea90949c78p-1",
        "0x1.799cb0794e18bp-1", "0x1.7818780f15cdep-1", "0x1.7691f4ee9cd69p-1",
        "0x1.75091beab2c21p-1", "0x1.737de181ace0dp-1", "0x1.71f039d9ec23fp-1",
        "0x1.706018be33e0fp-1", "0x1.6ecd7199ce6c0p-1", "0x1.6d3837747c3bdp-1",
        "0x1.6ba05cee2a08fp-1", "0x1.6a05d43a6a13ap-1", "0x1.68688f1bac6a7p-1",
        "0x1.66c87ede31b7fp-1", "0x1.65259452b3be3p-1", "0x1.637fbfc8be410p-1",
        "0x1.61d6f108b2adep-1", "0x1.602b174d70552p-1", "0x1.5e7c213d9a7f0p-1",
        "0x1.5cc9fce475118p-1", "0x1.5b1497aa4fd70p-1", "0x1.595bde4c77bdap-1",
        "0x1.579fbcd4a4a04p-1", "0x1.55e01e8fd9486p-1", "0x1.541cee04aa648p-1",
        "0x1.525614e8e0192p-1", "0x1.508b7c1664a65p-1", "0x1.4ebd0b7f7146ap-1",
        "0x1.4ceaaa21e8f53p-1", "0x1.4b143df9cf244p-1", "0x1.4939abf2c6975p-1",
        "0x1.475ad7d88287ap-1", "0x1.4577a44611ec0p-1", "0x1.438ff293ea270p-1",
        "0x1.41a3a2c49377dp-1", "0x1.3fb2936fd641cp-1", "0x1.3dbca1ac448b9p-1",
        "0x1.3bc1a8f6f6e95p-1", "0x1.39c183194f421p-1", "0x1.37bc080c8e81bp-1",
        "0x1.35b10ddb04206p-1", "0x1.33a0687e976aap-1", "0x1.3189e9bc62713p-1",
        "0x1.2f6d60fd0d57fp-1", "0x1.2d4a9b218e2ecp-1", "0x1.2b216253e554cp-1",
        "0x1.28f17dd360587p-1", "0x1.26bab1bbdd02fp-1", "0x1.247cbec7734edp-1",
        "0x1.22376209d704cp-1", "0x1.1fea54a4a7f20p-1", "0x1.1d954b73c9776p-1",
        "0x1.1b37f6b0b69fdp-1", "0x1.18d2018b9df36p-1", "0x1.166311b8de758p-1",
        "0x1.13eac6f1440a1p-1", "0x1.1168ba631abe0p-1", "0x1.0edc7e11db987p-1",
        "0x1.0c459c21cf550p-1", "0x1.09a3960c87a0fp-1", "0x1.06f5e3ba78dbcp-1",
        "0x1.043bf27d46371p-1", "0x1.017523e56fad1p-1", "0x1.fd4198d9f2a3fp-2",
        "0x1.f77c63de8e914p-2", "0x1.f19913c96b427p-2", "0x1.eb95eeac9ba6dp-2",
        "0x1.e57110f6837d5p-2", "0x1.df2867dcaeb27p-2", "0x1.d8b9aac9e12f1p-2",
        "0x1.d222539700f44p-2", "0x1.cb5f95471b53fp-2", "0x1.c46e50ea5e0d9p-2",
        "0x1.bd4b08307dbe2p-2", "0x1.b5f1cd0ddca72p-2", "0x1.ae5e2da3b40fbp-2",
        "0x1.a68b1b5456ccbp-2", "0x1.9e72cb87f01b8p-2", "0x1.960e90154589ap-2",
        "0x1.8d56a46dca4d8p-2", "0x1.8441eb6f16023p-2", "0x1.7ac597d6d3b82p-2",
        "0x1.70d4b65de8999p-2", "0x1.665f8bb53e5fcp-2", "0x1.5b52b0a3ccb32p-2",
        "0x1.4f95c8b9fa43bp-2", "0x1.43099728a392ap-2", "0x1.3585060437008p-2",
        "0x1.26d054de3547bp-2", "0x1.169cd473d93fep-2", "0x1.0475a7730776cp-2",
        "0x1.df41a2bff4a66p-3", "0x1.adaee6d2c6ba9p-3", "0x1.6ef3ca6af97b3p-3",
        "0x1.149c33f9c163dp-3", "0x0.0p+0",
    )]
)  # fmt: skip
ZIG_R = ZIG_X[1:] / ZIG_X[:-1]

_NONZERO = np.array(
    [0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB, 0x2545F4914F6CDD1D],
    dtype=np.uint64,
)


def path_states(seed: int, block: int, p: int) -> np.ndarray:
    """The xoshiro256** states of block ``block``'s ``p`` paths (see the module docstring).

    Parameters
    ----------
    seed : int
        The run's seed.
    block : int
        The block index.
    p : int
        Paths in the block.

    Returns
    -------
    numpy.ndarray
        (p, 4) uint64, one state per path.
    """
    words = np.random.SeedSequence(seed, spawn_key=(block,)).generate_state(4 * p, np.uint64)
    st = words.reshape(p, 4).copy()
    zero = ~st.any(axis=1)
    st[zero] = _NONZERO
    return st


def normals(states: np.ndarray, count: int) -> np.ndarray:
    """The next ``count`` normals of each path's stream, (p, count) (for tests and for
    whoever wants the streams themselves).

    Parameters
    ----------
    states : numpy.ndarray
        (p, 4) uint64, advanced in place.
    count : int
        Normals per path.

    Returns
    -------
    numpy.ndarray
    """
    from .kernels import fill_normals  # numba: only when drawing

    out = np.empty((1, states.shape[0], count))
    fill_normals(states, out)
    return out[0]


class NormalSource:
    """Block ``b``'s normals: ``fill(out)`` fills (K, p, m) in each path's stream order,
    continuing where the last call stopped; ``states`` is the xoshiro state the fused
    kernel draws from (None for NumPy's generator)."""

    def __init__(self, generator: str, seed: int, block: int, p: int):
        if generator not in GENERATORS:
            raise ValueError(f"generator: {generator!r} is not one of {GENERATORS}")
        self.generator = generator
        if generator == "numpy":
            self.states = None
            self._rng = np.random.Generator(
                np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(block,)))
            )
        else:
            self.states = path_states(seed, block, p)

    def fill(self, out: np.ndarray) -> None:
        """Fill ``out`` (K, p, m) with the next K steps' normals of every path.

        Parameters
        ----------
        out : numpy.ndarray
            Filled in place.
        """
        if self.states is None:
            self._rng.standard_normal(out=out)
        else:
            from .kernels import fill_normals  # numba: only when drawing

            fill_normals(self.states, out)


__all__ = ["GENERATORS", "ZIG_R", "ZIG_X", "NormalSource", "normals", "path_states"]
