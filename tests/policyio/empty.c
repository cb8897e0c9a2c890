/* An empty translation unit: the generated header under test is force-included. */
