"""What several deployment algorithms share, below them: steering rules, reference tracking, forces, stretches.

Algorithm packages (``self_spreading``, ``potential_field``, ``agent_assisted``, ``dssa``, ``vor``, ``minimax``,
``lloyd``) import from here and from
:mod:`amronet.algorithms.base` / :mod:`amronet.algorithms.stepping`, never from each other.
"""
