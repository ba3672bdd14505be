"""Dense LU factorisation with partial pivoting and its solve, in numba (real or complex; no LAPACK call
for the small systems of the Radau IIA Newton iteration)."""
from symmech.numerics.jit import inline, jit


@inline
def lu(A, piv):
    """LU factorisation with partial pivoting of A (n, n), real or complex, in place; row swaps into piv."""
    n = A.shape[0]
    for k in range(n):
        m = k
        for i in range(k + 1, n):
            if abs(A[i, k]) > abs(A[m, k]):
                m = i
        piv[k] = m
        for j in range(n):
            A[k, j], A[m, j] = A[m, j], A[k, j]
        for i in range(k + 1, n):
            if A[i, k] == 0.0:  # nothing to eliminate: the row is left as it is (the slip Jacobian is sparse)
                continue
            A[i, k] /= A[k, k]
            for j in range(k + 1, n):
                A[i, j] -= A[i, k] * A[k, j]


@jit
def lu_solve(LU, piv, b):
    """x with A x = b from the factors of :func:`lu`."""
    x = b.copy()
    solve_in_place(LU, piv, x)
    return x


@inline
def solve_in_place(LU, piv, x):
    """x (n,) overwritten by the solution of A x = b, b its value on entry, from the factors of :func:`lu`."""
    n = x.size
    for k in range(n):
        x[k], x[piv[k]] = x[piv[k]], x[k]
    for i in range(n):
        for j in range(i):
            x[i] -= LU[i, j] * x[j]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            x[i] -= LU[i, j] * x[j]
        x[i] /= LU[i, i]
