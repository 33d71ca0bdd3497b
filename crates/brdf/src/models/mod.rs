//! The BRDF models, one module per model, each citing its paper.

pub mod blinn_phong;
pub mod cook_torrance;
pub mod diefenbach_phong;
pub mod dielectric;
pub mod htsg;
pub mod lafortune;
pub mod lambert;
pub mod lewis;
pub mod mixture;
pub mod modified_phong;
pub mod oren_nayar;
pub mod phong;
pub mod poulin_fournier;
pub mod schlick;
pub mod specular;
pub mod strauss;
pub mod torrance_sparrow;
pub mod ward;

pub use blinn_phong::BlinnPhong;
pub use cook_torrance::CookTorrance;
pub use diefenbach_phong::DiefenbachPhong;
pub use dielectric::SmoothDielectric;
pub use htsg::Htsg;
pub use lafortune::{CosineLobe, Lafortune};
pub use lambert::Lambert;
pub use lewis::lewis;
pub use mixture::{BoxedBrdf, Mixture};
pub use modified_phong::ModifiedPhong;
pub use oren_nayar::{OrenNayarFull, OrenNayarQualitative};
pub use phong::Phong;
pub use poulin_fournier::PoulinFournier;
pub use schlick::Schlick;
pub use specular::SpecularReflection;
pub use strauss::Strauss;
pub use torrance_sparrow::torrance_sparrow;
pub use ward::{Ward, WardNormalisation};
