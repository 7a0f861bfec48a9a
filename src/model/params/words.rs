//! Parameters whose value is a word naming an enum variant, the words declared once with
//! their variants (`word_enum!`): the scene's and the command line's choice list, the
//! reading and the naming follow from it.

/// Defines an enum whose variants are named by words (`Variant = "word"`): `WORDS` (in
/// order), `word()` and `from_word()`. Serde and clap derive the same words (kebab-case;
/// a test checks).
macro_rules! word_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident = $word:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis enum $name {
            $( $(#[$vmeta])* $variant ),+
        }

        impl $name {
            /// The words naming the variants, in order (scenes and the command line).
            pub const WORDS: &'static [&'static str] = &[$($word),+];

            /// The word naming this variant.
            pub const fn word(self) -> &'static str {
                match self {
                    $(Self::$variant => $word),+
                }
            }

            /// The variant `word` names, if any.
            pub fn from_word(word: &str) -> Option<Self> {
                match word {
                    $($word => Some(Self::$variant),)+
                    _ => None,
                }
            }
        }
    };
}
pub(crate) use word_enum;
